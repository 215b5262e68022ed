//! Which hosts the ranks run on: a DEM joins rank 0 over shared memory (iceoryx2), on rank 0's
//! host, so a run with particles keeps its ranks on that one host ([`dem_hosts`]).

use super::Communicator;

/// Every rank's host at rank 0, in rank order (MPI's processor name; empty elsewhere).
pub fn hosts(comm: &dyn Communicator) -> Vec<String> {
    let gathered = comm.gather(comm.host().as_bytes());
    gathered
        .iter()
        .map(|h| String::from_utf8_lossy(h).into_owned())
        .collect()
}

/// The ranks of a run with particles on the hosts `hosts` (rank order; none known: allowed):
/// refused where they are on more than one, saying that the DEM must be on rank 0's host.
pub fn dem_hosts(hosts: &[String]) -> Result<(), String> {
    let mut names: Vec<&String> = hosts.iter().collect();
    names.sort();
    names.dedup();
    if names.len() <= 1 {
        return Ok(());
    }
    let on = names
        .iter()
        .map(|name| {
            let ranks: Vec<String> = (0..hosts.len())
                .filter(|&r| hosts[r] == **name)
                .map(|r| r.to_string())
                .collect();
            format!("{name}: rank {}", ranks.join(", "))
        })
        .collect::<Vec<_>>()
        .join("; ");
    Err(format!(
        "{} ranks on {} hosts ({on}), and the scene has particles: the DEM joins rank 0 over \
         shared memory (iceoryx2), so it must run on rank 0's host ({}), and a run with particles \
         keeps all its ranks there (mpirun --host {}:{} ..., srun --nodes=1); fluid-only scenes \
         run across hosts",
        hosts.len(),
        names.len(),
        hosts[0],
        hosts[0],
        hosts.len()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranks_on_several_hosts_with_a_dem_are_refused_naming_rank_0s_host() {
        let one = ["a".to_string(), "a".to_string()];
        assert!(dem_hosts(&one).is_ok());
        let two = ["n1", "n2", "n1", "n2"].map(String::from);
        let e = dem_hosts(&two).unwrap_err();
        assert!(
            e.contains("4 ranks on 2 hosts (n1: rank 0, 2; n2: rank 1, 3)"),
            "{e}"
        );
        assert!(e.contains("must run on rank 0's host (n1)"), "{e}");
    }
}

//! The handshake refuses what cannot work, and two runs at once never see each other.

mod common;
use common::*;
use std::time::Duration;

#[test]
fn protocol_version_mismatch_is_refused_naming_both_versions() {
    let dir = temp_dir("version");
    let scene = write_scene(&dir, &scene_text("version", [2, 2, 2], 50, 10, 10.0));
    let out = dir.join("out");
    let (mut server, run) = start_external(&scene, &out);
    let client = std::process::Command::new(bin("dem-client"))
        .args(["connect", "--service", &run, "--protocol-version", "7", "--scene"])
        .arg(&scene)
        .output()
        .unwrap();
    let client_err = String::from_utf8_lossy(&client.stderr);
    assert_eq!(client.status.code(), Some(1), "{client_err}");
    let (code, _) = server.wait_exit(PROCESS_WAIT);
    let server_err = Proc::drain(&server.stderr);
    assert_eq!(code, Some(1));
    let expected = "protocol version mismatch: lbm-server speaks version 2, the DEM client speaks version 7";
    assert!(server_err.contains(expected), "{server_err}");
    assert!(client_err.contains(expected), "{client_err}");
    assert_eq!(summary(&out)["steps_completed"], 0);
    assert!(leftover_files(&run).is_empty());
}

#[test]
fn joining_a_run_that_does_not_exist_fails_clearly() {
    let out = std::process::Command::new(bin("dem-client"))
        .args(["connect", "--service", "lbmdem_1_nosuchrun", "--timeout", "0.3"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(err.contains("no run named 'lbmdem_1_nosuchrun' found"), "{err}");
    assert!(
        leftover_files("lbmdem_1_nosuchrun").is_empty(),
        "{:?}",
        leftover_files("lbmdem_1_nosuchrun")
    );
}

#[test]
fn two_runs_at_the_same_time_do_not_interfere() {
    let runs: Vec<_> = [("left", [3, 3, 3], 250), ("right", [5, 4, 2], 300)]
        .into_iter()
        .map(|(tag, count, steps)| {
            let dir = temp_dir(tag);
            let scene = write_scene(&dir, &scene_text(tag, count, steps, 100, 10.0));
            let out = dir.join("out");
            (
                start(server(&scene, &out, &[])),
                out,
                count.iter().product::<u64>(),
                steps,
            )
        })
        .collect();
    for (mut server, out, n, steps) in runs {
        let (code, _) = server.wait_exit(Duration::from_secs(120));
        assert_eq!(code, Some(0), "{}", Proc::drain(&server.stderr));
        let s = summary(&out);
        assert_eq!(s["particles_initial"], n);
        assert_eq!(s["steps_completed"], steps);
        let rows = csv_steps(&out);
        assert!(rows.values().all(|ids| ids.len() as u64 == n));
    }
}

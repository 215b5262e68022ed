//! The checksum of a checkpoint's files (docs/checkpoint.md): 64-bit FNV-1a, written as 16 hex
//! digits. Shared by lbm-server and dem-client, each of which writes part of a checkpoint.

/// FNV-1a 64 of `bytes`, continuing from `hash` (start from [`FNV_OFFSET`]).
pub fn fnv1a64_from(hash: u64, bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(hash, |h, &b| (h ^ b as u64).wrapping_mul(FNV_PRIME))
}

pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a 64 of `bytes` as 16 hex digits.
pub fn fnv1a64(bytes: &[u8]) -> String {
    format!("{:016x}", fnv1a64_from(FNV_OFFSET, bytes))
}

/// The checksum of the file at `path`, and its size in bytes.
pub fn of_file(path: &std::path::Path) -> std::io::Result<(String, u64)> {
    let bytes = std::fs::read(path)?;
    Ok((fnv1a64(&bytes), bytes.len() as u64))
}

#[cfg(test)]
mod tests {
    #[test]
    fn fnv1a64_of_known_strings() {
        assert_eq!(super::fnv1a64(b""), "cbf29ce484222325");
        assert_eq!(super::fnv1a64(b"a"), "af63dc4c8601ec8c");
    }
}

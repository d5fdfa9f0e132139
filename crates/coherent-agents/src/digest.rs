//! Stable hashes of text: the same on every machine, run and version (unlike the
//! standard library's hasher), for names that must not change: a prompt set's, a run's
//! settings'.

/// FNV-1a, 128 bits, of each `(name, text)` with a 0 byte after each part.
pub fn fnv128<'a>(parts: impl IntoIterator<Item = (&'a str, &'a str)>) -> String {
    const PRIME: u128 = 0x0000_0000_0100_0000_0000_0000_0000_013b;
    let mut h: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d;
    for (name, text) in parts {
        for bytes in [name.as_bytes(), text.as_bytes()] {
            for &b in bytes.iter().chain(&[0]) {
                h ^= u128::from(b);
                h = h.wrapping_mul(PRIME);
            }
        }
    }
    format!("{h:032x}")
}

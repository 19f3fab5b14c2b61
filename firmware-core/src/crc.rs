//! CRC-32 (IEEE 802.3, reflected, poly 0xEDB88320) with a 16-entry table: 64 bytes of
//! flash instead of 1 KiB, fast enough for a blob decoded once at start-up.
#![deny(clippy::arithmetic_side_effects)]

// Evaluated at compile time: an out-of-range index or overflow fails the build, not the MCU.
#[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
const TABLE: [u32; 16] = {
    let mut t = [0u32; 16];
    let mut i = 0;
    while i < 16 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 4 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

fn nibble(c: u32) -> u32 {
    // `c & 0xF` is always < 16: `get` keeps the code free of panicking paths anyway.
    let low = (c & 0xF) as usize;
    (c >> 4) ^ TABLE.get(low).copied().unwrap_or(0)
}

/// CRC-32 of `data` (the zlib / PNG / Ethernet CRC).
pub fn crc32(data: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in data {
        c ^= u32::from(b);
        c = nibble(nibble(c));
    }
    !c
}

#[cfg(test)]
mod tests {
    #[test]
    fn check_value() {
        assert_eq!(super::crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(super::crc32(b""), 0);
    }
}

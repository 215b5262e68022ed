//! How the populations are stored on the device (`lattice.storage`): FP32, or 16 bits (IEEE half,
//! FP16S, or a custom float with one more mantissa bit, FP16C) two cells to a u32 word, the
//! arithmetic in f32 either way. The shaders' load/store pair of each storage lives in
//! shaders/storage_fp32.wgsl and shaders/storage_fp16.wgsl (with fp16s.wgsl or fp16c.wgsl); the
//! same conversions here serve the upload and the readback.

pub use scene::lattice::Storage;

/// What the device does with a storage (`lattice.storage`, scene's [`Storage`]): its buffers,
/// shaders and the conversions of the upload and the readback.
pub trait StorageOnDevice: Copy {
    fn buffer_bytes(self, cells: usize) -> u64;
    fn shader(self) -> String;
    fn access_shader(self) -> String;
    #[cfg(test)]
    fn rounding_bound(self, x: f64) -> f64;
    fn encode(self, values: &[f32]) -> Vec<u8>;
    fn decode(self, bytes: &[u8], cells: usize) -> Vec<f32>;
    #[cfg(test)]
    fn round(self, x: f32) -> f32;
}

impl StorageOnDevice for Storage {
    /// Bytes of a direction's buffer for `cells` cells (whole u32 words, rounded up to 16 bytes).
    fn buffer_bytes(self, cells: usize) -> u64 {
        ((cells * self.bytes()) as u64).div_ceil(16) * 16
    }

    /// The shader source of the storage's buffers and load/store pair (with the four-cell quads
    /// for FP32).
    fn shader(self) -> String {
        const QUADS: &str = include_str!("../../../shaders/quads.wgsl");
        match self {
            Storage::Fp32 => format!("{}\n{QUADS}", self.access_shader()),
            _ => self.access_shader(),
        }
    }

    /// The shader source of the storage's buffers and load/store pair alone (the halo kernels,
    /// halo.wgsl).
    fn access_shader(self) -> String {
        const FP32: &str = include_str!("../../../shaders/storage_fp32.wgsl");
        const FP16: &str = include_str!("../../../shaders/storage_fp16.wgsl");
        const FP16S: &str = include_str!("../../../shaders/fp16s.wgsl");
        const FP16C: &str = include_str!("../../../shaders/fp16c.wgsl");
        match self {
            Storage::Fp32 => FP32.to_string(),
            Storage::Fp16s => format!("{FP16}\n{FP16S}"),
            Storage::Fp16c => format!("{FP16}\n{FP16C}"),
        }
    }

    /// Bound on the rounding error of one stored value x: relative 2^-(p+1) for p mantissa bits,
    /// and half the subnormal step near zero (round to nearest).
    #[cfg(test)]
    fn rounding_bound(self, x: f64) -> f64 {
        match self {
            Storage::Fp32 => 0.0,
            Storage::Fp16s => (x.abs() * 2f64.powi(-11)).max(2f64.powi(-25)),
            Storage::Fp16c => (x.abs() * 2f64.powi(-12)).max(2f64.powi(-26)),
        }
    }

    /// The buffer of one direction's populations, from f32 values in cell order.
    fn encode(self, values: &[f32]) -> Vec<u8> {
        match self {
            Storage::Fp32 => bytemuck::cast_slice(values).to_vec(),
            _ => {
                let halves: Vec<u16> = values.iter().map(|&v| encode16(self, v)).collect();
                bytemuck::cast_slice(&halves).to_vec()
            }
        }
    }

    /// f32 values in cell order (the first `cells`) from one direction's buffer.
    fn decode(self, bytes: &[u8], cells: usize) -> Vec<f32> {
        match self {
            Storage::Fp32 => bytemuck::cast_slice::<u8, f32>(bytes)[..cells].to_vec(),
            _ => bytes[..cells * 2]
                .chunks_exact(2)
                .map(|b| decode16(self, u16::from_le_bytes([b[0], b[1]])))
                .collect(),
        }
    }

    /// The value as stored, in f32: what a store followed by a load gives.
    #[cfg(test)]
    fn round(self, x: f32) -> f32 {
        match self {
            Storage::Fp32 => x,
            _ => decode16(self, encode16(self, x)),
        }
    }
}

/// One value's 16 bits in `storage` (FP16S or FP16C).
fn encode16(storage: Storage, x: f32) -> u16 {
    match storage {
        Storage::Fp16c => fp16c_encode(x),
        _ => half::f16::from_f32(x).to_bits(),
    }
}

/// The value of 16 bits in `storage` (FP16S or FP16C).
fn decode16(storage: Storage, h: u16) -> f32 {
    match storage {
        Storage::Fp16c => fp16c_decode(h),
        _ => half::f16::from_bits(h).to_f32(),
    }
}

/// FP16C of x (shaders/fp16c.wgsl's `encode16`): the f32 exponent rebiased from 127 to 15 and the
/// mantissa rounded to 11 bits to nearest even; below 2^-14 steps of 2^-25; saturated at 2.
pub fn fp16c_encode(x: f32) -> u16 {
    let bits = x.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let a = bits & 0x7fff_ffff;
    if a >= 0x4000_0000 {
        return sign | 0x7fff;
    }
    let magnitude = if a >= 113 << 23 {
        let n = a - (112 << 23);
        ((n + 0x7ff + ((n >> 12) & 1)) >> 12).min(0x7fff)
    } else {
        (x.abs() * 2f32.powi(25)).round_ties_even() as u32
    };
    sign | magnitude as u16
}

/// The value of an FP16C word (shaders/fp16c.wgsl's `decode16`).
pub fn fp16c_decode(h: u16) -> f32 {
    let magnitude = u32::from(h & 0x7fff);
    let value = if magnitude >= 0x800 {
        f32::from_bits((magnitude << 12) + (112 << 23))
    } else {
        magnitude as f32 * 2f32.powi(-25)
    };
    if h & 0x8000 != 0 {
        -value
    } else {
        value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every FP16C word decodes to a value that encodes back to it, and rounding stays within
    /// half a step.
    #[test]
    fn fp16c_round_trips_and_rounds_to_nearest() {
        for h in 0..=u16::MAX {
            assert_eq!(fp16c_encode(fp16c_decode(h)), h, "{h:#x}");
        }
        for &x in &[1e-9f32, 3.1e-8, 6.1e-5, 1.0e-3, -0.0123, 0.3333, 1.5, -1.9999] {
            let err = (Storage::Fp16c.round(x) - x).abs() as f64;
            assert!(err <= Storage::Fp16c.rounding_bound(x as f64), "{x}: {err:e}");
            let err = (Storage::Fp16s.round(x) - x).abs() as f64;
            assert!(err <= Storage::Fp16s.rounding_bound(x as f64), "{x}: {err:e}");
        }
        assert_eq!(fp16c_decode(fp16c_encode(5.0)), 2.0 - 2f32.powi(-11), "saturates");
    }
}

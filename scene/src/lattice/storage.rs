//! `lattice.storage`: how the populations are stored on the device (lbm-server's
//! `lbm/storage.rs` holds their encoding and shaders).

/// The storage of the populations (f_i - w_i); the arithmetic is f32 either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Storage {
    #[default]
    Fp32,
    /// IEEE 754 half: 10 mantissa bits, 5 exponent bits.
    Fp16s,
    /// 11 mantissa bits, 4 exponent bits, |value| < 2 (FluidX3D's FP16C idea).
    Fp16c,
}

impl Storage {
    pub const ALL: [Storage; 3] = [Storage::Fp32, Storage::Fp16s, Storage::Fp16c];

    /// The name in scenes and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Storage::Fp32 => "fp32",
            Storage::Fp16s => "fp16s",
            Storage::Fp16c => "fp16c",
        }
    }

    pub fn named(name: &str) -> Option<Storage> {
        Storage::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Bytes of one population.
    pub fn bytes(self) -> usize {
        match self {
            Storage::Fp32 => 4,
            _ => 2,
        }
    }
}

impl std::fmt::Display for Storage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

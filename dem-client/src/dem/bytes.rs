//! The DEM's state as bytes (dem.bin of a checkpoint): little-endian numbers, vectors as a u64
//! length and their elements, written by an [`Encoder`] and read back by a [`Decoder`] that
//! names what it misses.

use super::V3;

/// Writes numbers and vectors of them.
#[derive(Default)]
pub struct Encoder {
    pub bytes: Vec<u8>,
}

impl Encoder {
    pub fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    pub fn f64(&mut self, v: f64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    pub fn v3(&mut self, v: &V3) {
        for x in v.iter() {
            self.f64(*x);
        }
    }

    /// A vector: its length, then each element by `put`.
    pub fn list<T>(&mut self, items: &[T], mut put: impl FnMut(&mut Self, &T)) {
        self.u64(items.len() as u64);
        for item in items {
            put(self, item);
        }
    }

    pub fn v3s(&mut self, items: &[V3]) {
        self.list(items, |e, v| e.v3(v));
    }

    pub fn u32s(&mut self, items: &[u32]) {
        self.list(items, |e, v| e.u64(*v as u64));
    }
}

/// Reads what an [`Encoder`] wrote.
pub struct Decoder<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Decoder<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    fn take8(&mut self) -> Result<[u8; 8], String> {
        let end = self.at + 8;
        let chunk = self.bytes.get(self.at..end).ok_or_else(|| {
            format!(
                "dem.bin ends at byte {} where more was written (truncated)",
                self.bytes.len()
            )
        })?;
        self.at = end;
        Ok(chunk.try_into().expect("8 bytes"))
    }

    pub fn u64(&mut self) -> Result<u64, String> {
        self.take8().map(u64::from_le_bytes)
    }

    pub fn f64(&mut self) -> Result<f64, String> {
        self.take8().map(f64::from_le_bytes)
    }

    pub fn v3(&mut self) -> Result<V3, String> {
        Ok(V3::new(self.f64()?, self.f64()?, self.f64()?))
    }

    /// A vector written by `Encoder::list`, each element read by `get`.
    pub fn list<T>(&mut self, mut get: impl FnMut(&mut Self) -> Result<T, String>) -> Result<Vec<T>, String> {
        let n = self.u64()? as usize;
        if n > self.bytes.len() {
            return Err(format!(
                "dem.bin: a list of {n} elements is longer than the file (corrupt)"
            ));
        }
        (0..n).map(|_| get(self)).collect()
    }

    pub fn v3s(&mut self) -> Result<Vec<V3>, String> {
        self.list(|d| d.v3())
    }

    pub fn u32s(&mut self) -> Result<Vec<u32>, String> {
        self.list(|d| d.u64().map(|v| v as u32))
    }

    /// Whether every byte was read.
    pub fn done(&self) -> bool {
        self.at == self.bytes.len()
    }
}

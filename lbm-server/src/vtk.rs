//! ParaView output of the fluid: VTK image data (.vti, raw appended binary) and a .pvd series.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Where and how big the grid is, in SI units.
#[derive(Debug, Clone, Copy)]
pub struct Grid {
    pub n: [usize; 3],
    pub origin: [f64; 3],
    pub dx: f64,
}

/// Writes density [kg/m^3] and velocity [m/s] per cell as a .vti file.
pub fn write_vti(path: &Path, grid: &Grid, density: &[f32], velocity: &[[f32; 3]]) -> std::io::Result<()> {
    let [nx, ny, nz] = grid.n;
    let cells = nx * ny * nz;
    let mut w = BufWriter::new(File::create(path)?);
    let density_bytes = (cells * 4) as u64;
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
    )?;
    let [ox, oy, oz] = grid.origin;
    let dx = grid.dx;
    writeln!(
        w,
        r#"<ImageData WholeExtent="0 {nx} 0 {ny} 0 {nz}" Origin="{ox} {oy} {oz}" Spacing="{dx} {dx} {dx}">"#
    )?;
    writeln!(w, r#"<Piece Extent="0 {nx} 0 {ny} 0 {nz}">"#)?;
    writeln!(w, r#"<CellData Scalars="density" Vectors="velocity">"#)?;
    writeln!(
        w,
        r#"<DataArray type="Float32" Name="density" format="appended" offset="0"/>"#
    )?;
    writeln!(
        w,
        r#"<DataArray type="Float32" Name="velocity" NumberOfComponents="3" format="appended" offset="{}"/>"#,
        8 + density_bytes
    )?;
    writeln!(w, "</CellData>\n</Piece>\n</ImageData>")?;
    write!(w, r#"<AppendedData encoding="raw">_"#)?;
    w.write_all(&density_bytes.to_le_bytes())?;
    w.write_all(bytemuck::cast_slice(density))?;
    w.write_all(&(3 * density_bytes).to_le_bytes())?;
    w.write_all(bytemuck::cast_slice(velocity))?;
    writeln!(w, "\n</AppendedData>\n</VTKFile>")?;
    w.flush()
}

/// A .pvd time series, rewritten whole after every snapshot so that it is always complete.
pub struct Series {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl Series {
    pub fn new(path: PathBuf) -> Self {
        Self {
            path,
            entries: Vec::new(),
        }
    }

    /// The series of a resumed run, its entries so far (a checkpoint's; the .pvd was cut back to
    /// them by `scene::checkpoint::cut_back`).
    pub fn resume(path: PathBuf, entries: Vec<(f64, String)>) -> std::io::Result<Self> {
        Ok(Self { path, entries })
    }

    /// The entries so far: time [s] and file (relative to the .pvd).
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// Adds `file` (relative to the .pvd) at simulation time `time` [s].
    pub fn add(&mut self, time: f64, file: &str) -> std::io::Result<()> {
        self.entries.push((time, file.to_string()));
        self.write()
    }

    /// Writes the .pvd with the entries so far.
    fn write(&self) -> std::io::Result<()> {
        let mut text = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
        );
        for (t, f) in &self.entries {
            text += &format!("<DataSet timestep=\"{t:e}\" file=\"{f}\"/>\n");
        }
        text += "</Collection>\n</VTKFile>\n";
        std::fs::write(&self.path, text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vti_has_consistent_header_and_payload_sizes() {
        let dir = std::env::temp_dir().join(format!("vti-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.vti");
        let grid = Grid {
            n: [2, 3, 1],
            origin: [0.0; 3],
            dx: 0.5,
        };
        write_vti(&path, &grid, &[1.0; 6], &[[0.5, 0.0, -1.0]; 6]).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let marker = b"encoding=\"raw\">_";
        let start = bytes.windows(marker.len()).position(|w| w == marker).unwrap() + marker.len();
        let len = u64::from_le_bytes(bytes[start..start + 8].try_into().unwrap());
        assert_eq!(len, 24);
        let second = start + 8 + 24;
        let len2 = u64::from_le_bytes(bytes[second..second + 8].try_into().unwrap());
        assert_eq!(len2, 72);
        let text = String::from_utf8_lossy(&bytes[..start]);
        assert!(text.contains(r#"offset="32""#), "{text}");
        std::fs::remove_dir_all(dir).unwrap();
    }
}

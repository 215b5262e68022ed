//! ParaView output of the fluid: VTK image data (.vti, raw appended binary), parallel image data
//! (.pvti, naming one .vti piece per rank) and a .pvd series.

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

/// A box of a grid's cells: its first cell and its cells along each axis (a rank's block).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Extent {
    pub first: [usize; 3],
    pub size: [usize; 3],
}

impl Extent {
    /// All the cells of a grid of `n` cells.
    pub fn whole(n: [usize; 3]) -> Extent {
        Extent {
            first: [0; 3],
            size: n,
        }
    }

    /// As VTK writes an extent: the first and last point along x, y and z.
    fn points(&self) -> String {
        let [a, b, c] = std::array::from_fn(|i| (self.first[i], self.first[i] + self.size[i]));
        format!("{} {} {} {} {} {}", a.0, a.1, b.0, b.1, c.0, c.1)
    }

    fn cells(&self) -> usize {
        self.size.iter().product()
    }
}

/// Writes density [kg/m^3] and velocity [m/s] per cell as a .vti file.
pub fn write_vti(path: &Path, grid: &Grid, density: &[f32], velocity: &[[f32; 3]]) -> std::io::Result<()> {
    write_vti_piece(path, grid, Extent::whole(grid.n), density, velocity)
}

/// Writes density and velocity of the cells `extent` of `grid` (x fastest) as a .vti file: a
/// piece of a .pvti ([`write_pvti`]), placed in the grid by its extent (the grid's origin and
/// spacing, its own cells' indices), or the whole grid.
pub fn write_vti_piece(
    path: &Path,
    grid: &Grid,
    extent: Extent,
    density: &[f32],
    velocity: &[[f32; 3]],
) -> std::io::Result<()> {
    let mut w = BufWriter::new(File::create(path)?);
    let density_bytes = (extent.cells() * 4) as u64;
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
    )?;
    let [ox, oy, oz] = grid.origin;
    let (dx, points) = (grid.dx, extent.points());
    writeln!(
        w,
        r#"<ImageData WholeExtent="{points}" Origin="{ox} {oy} {oz}" Spacing="{dx} {dx} {dx}">"#
    )?;
    writeln!(w, r#"<Piece Extent="{points}">"#)?;
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

/// Writes a .pvti: ParaView's parallel image data, the whole `grid` as the `pieces` (each a .vti
/// by [`write_vti_piece`], named relative to the .pvti, with its extent) that cover it.
pub fn write_pvti(path: &Path, grid: &Grid, pieces: &[(Extent, String)]) -> std::io::Result<()> {
    let [ox, oy, oz] = grid.origin;
    let (dx, whole) = (grid.dx, Extent::whole(grid.n).points());
    let mut text = String::from("<?xml version=\"1.0\"?>\n");
    text += r#"<VTKFile type="PImageData" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#;
    text += &format!(
        "\n<PImageData WholeExtent=\"{whole}\" GhostLevel=\"0\" Origin=\"{ox} {oy} {oz}\" \
         Spacing=\"{dx} {dx} {dx}\">\n"
    );
    text += "<PCellData Scalars=\"density\" Vectors=\"velocity\">\n";
    text += "<PDataArray type=\"Float32\" Name=\"density\"/>\n";
    text += "<PDataArray type=\"Float32\" Name=\"velocity\" NumberOfComponents=\"3\"/>\n";
    text += "</PCellData>\n";
    for (extent, source) in pieces {
        text += &format!("<Piece Extent=\"{}\" Source=\"{source}\"/>\n", extent.points());
    }
    text += "</PImageData>\n</VTKFile>\n";
    std::fs::write(path, text)
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

//! The immersed boundary's accuracy as validation/lbm/REPORT.md measured it: the drag error and
//! the hydrodynamic radius deficit against tau, and the Stokes drag of spheres of a few cells.
//! The radius correction (`radius_correction.rs`) and the warnings (`warnings.rs`) read these
//! tables; the tests below hold them against the report.

/// The immersed boundary's drag error against tau, measured (validation/lbm/REPORT.md, "drag
/// against tau": the Zick-Homsy array at solid fraction 0.125, sphere radius 4.96 cells,
/// Noble-Torczynski weighting): (tau, [BGK, TRT, MRT] in %). TRT at 7.44 cells: about half.
pub(super) const DRAG_AGAINST_TAU: [(f64, [f64; 3]); 7] = [
    (0.55, [1.9, -4.0, 2.4]),
    (0.6, [0.1, -5.1, 0.5]),
    (0.7, [-3.1, -6.7, -2.0]),
    (0.8, [-6.1, -8.2, -3.9]),
    (1.0, [-11.8, -10.7, -7.0]),
    (1.5, [-25.1, -16.1, -13.5]),
    (2.0, [-36.8, -20.7, -19.0]),
];

/// The immersed boundary's hydrodynamic radius deficit against tau, measured
/// (validation/lbm/REPORT.md, "hydrodynamic radius deficit against tau": the array of
/// [`DRAG_AGAINST_TAU`] drawn larger until its drag is Zick & Homsy's, nominal radius
/// [`deficit_radius`] cells): (tau, [BGK, TRT, MRT] in cells). At 7.44 cells TRT's deficit is
/// 0.56-0.66 of these: the deficit falls as 1 / radius (second-order convergence).
pub(super) const RADIUS_DEFICIT: [(f64, [f64; 3]); 7] = [
    (0.55, [-0.029, 0.068, -0.036]),
    (0.6, [-0.001, 0.086, -0.008]),
    (0.7, [0.051, 0.116, 0.031]),
    (0.8, [0.102, 0.142, 0.063]),
    (1.0, [0.215, 0.192, 0.118]),
    (1.5, [0.566, 0.308, 0.247]),
    (2.0, [1.023, 0.423, 0.374]),
];

/// The nominal radius (cells) of [`RADIUS_DEFICIT`]: solid fraction 0.125 in a 16^3 box.
pub(super) fn deficit_radius() -> f64 {
    (0.125 * 4096.0 * 3.0 / (4.0 * std::f64::consts::PI)).cbrt()
}

/// The column of `operator` in the measured tables (BGK, TRT, MRT).
pub(super) fn operator_index(operator: &str) -> Option<usize> {
    ["bgk", "trt", "mrt"].iter().position(|o| *o == operator)
}

/// A measured table's value for `operator` at `tau`, interpolated linearly between the measured
/// taus (the first one's below them); None beyond the last measured tau.
pub(super) fn measured_at(table: &[(f64, [f64; 3])], operator: &str, tau: f64) -> Option<f64> {
    let k = operator_index(operator)?;
    let (first, last) = (table[0], table[table.len() - 1]);
    if tau <= first.0 {
        return Some(first.1[k]);
    }
    if tau > last.0 {
        return None;
    }
    let upper = table.iter().position(|&(t, _)| t >= tau)?;
    let ((t0, e0), (t1, e1)) = (table[upper - 1], table[upper]);
    if t1 == tau {
        return Some(e1[k]);
    }
    Some(e0[k] + (e1[k] - e0[k]) * (tau - t0) / (t1 - t0))
}

/// The measured drag error of `operator` at `tau` ([`DRAG_AGAINST_TAU`], in %).
pub(super) fn drag_error_at(operator: &str, tau: f64) -> Option<f64> {
    measured_at(&DRAG_AGAINST_TAU, operator, tau)
}

/// Stokes drag of spheres of a few cells, by diameter in cells (validation/lbm/REPORT.md,
/// "spheres of a few cells and less": a dilute array against Sangani & Acrivos; TRT moving
/// through the lattice, BGK and MRT at rest): (diameter, [BGK, TRT, MRT] x [tau 0.6, tau 1]) in %.
pub(super) const SMALL_SPHERE_DRAG: [(f64, [[f64; 2]; 3]); 7] = [
    (0.5, [[-100.0, -100.0], [-100.1, -100.0], [-100.0, -100.0]]),
    (1.0, [[-100.0, -100.0], [-91.9, -94.1], [-100.0, -100.0]]),
    (1.5, [[-61.5, -72.3], [-63.8, -73.0], [-61.5, -71.3]]),
    (2.0, [[-41.0, -58.2], [-44.9, -57.1], [-40.9, -55.1]]),
    (3.0, [[-10.3, -33.2], [-22.4, -34.0], [-9.5, -26.4]]),
    (4.0, [[-10.5, -26.0], [-15.8, -22.2], [-10.2, -20.9]]),
    (6.0, [[-4.5, -16.6], [-9.5, -15.3], [-4.2, -11.7]]),
];

/// The spheres of [`SMALL_SPHERE_DRAG`] moving with TRT, drawn larger as
/// `coupling.radius_correction = "calibrated"` draws them (the same section of the report):
/// (diameter, [tau 0.6, tau 1]) in %.
pub(super) const SMALL_SPHERE_DRAG_CALIBRATED: [(f64, [f64; 2]); 6] = [
    (1.0, [-51.8, -10.4]),
    (1.5, [-29.3, -0.3]),
    (2.0, [-14.9, 7.8]),
    (3.0, [-4.3, 10.4]),
    (4.0, [1.7, 12.7]),
    (6.0, [-0.7, 4.2]),
];

/// A table's values (tau 0.6, tau 1) at `d` cells per diameter, linear between its diameters and
/// its end rows' beyond them.
pub(super) fn at_diameter(table: &[(f64, [f64; 2])], d: f64) -> [f64; 2] {
    let upper = table
        .iter()
        .position(|r| r.0 >= d)
        .unwrap_or(table.len() - 1)
        .max(1);
    let ((d0, e0), (d1, e1)) = (table[upper - 1], table[upper]);
    let w = ((d - d0) / (d1 - d0)).clamp(0.0, 1.0);
    std::array::from_fn(|t| e0[t] + (e1[t] - e0[t]) * w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drag_error_is_the_measured_one_between_the_measured_taus() {
        assert_eq!(drag_error_at("trt", 1.0), Some(-10.7));
        assert_eq!(
            drag_error_at("bgk", 0.3),
            Some(1.9),
            "below the table: its first row"
        );
        let mid = drag_error_at("mrt", 1.25).unwrap();
        assert!((mid - (-7.0 - 13.5) / 2.0).abs() < 1e-12, "{mid}");
        assert_eq!(drag_error_at("trt", 2.5), None, "beyond the table");
        assert_eq!(drag_error_at("lbgk", 1.0), None);
    }

    /// The rows of the 16^3 box in a section of validation/lbm/REPORT.md: (tau, operator, the
    /// number in column `column` without its % sign).
    fn report_rows(heading: &str, column: usize) -> Vec<(f64, String, f64)> {
        let section = crate::validate::report_section(heading);
        let rows = section.lines().filter(|l| l.starts_with("| 16 |")).map(|line| {
            let cells: Vec<&str> = line.split('|').map(str::trim).collect();
            let number = cells[column].trim_end_matches('%').parse().unwrap();
            (cells[3].parse().unwrap(), cells[4].to_string(), number)
        });
        rows.collect()
    }

    #[test]
    fn the_drag_table_is_the_reports() {
        let rows = report_rows("## Immersed moving boundary: drag against tau", 8);
        for (tau, op, error) in &rows {
            assert_eq!(drag_error_at(op, *tau), Some(*error), "{op} at tau {tau}");
        }
        assert_eq!(rows.len(), 3 * DRAG_AGAINST_TAU.len());
    }

    #[test]
    fn the_radius_deficit_table_is_the_reports() {
        let heading = "## Immersed moving boundary: hydrodynamic radius deficit against tau";
        let rows = report_rows(heading, 7);
        for (tau, op, delta) in &rows {
            assert_eq!(
                measured_at(&RADIUS_DEFICIT, op, *tau),
                Some(*delta),
                "{op} at tau {tau}"
            );
        }
        assert_eq!(rows.len(), 3 * RADIUS_DEFICIT.len());
    }

    /// SMALL_SPHERE_DRAG holds the runs of validation/lbm/REPORT.md's section, row by row: BGK
    /// and MRT at rest, TRT moving.
    #[test]
    fn the_small_sphere_drag_is_the_reports() {
        let section =
            crate::validate::report_section("## Immersed moving boundary: spheres of a few cells and less");
        for (d, [bgk, trt, mrt]) in SMALL_SPHERE_DRAG {
            let row = section
                .lines()
                .find(|l| l.starts_with(&format!("| {d:.1} |")))
                .unwrap_or_else(|| panic!("no row for {d} cells"));
            let cells: Vec<&str> = row.split(" | ").collect();
            let pct = |e: f64| format!("{e:+.1}%");
            let expected = [bgk[0], bgk[1], trt[0], trt[1], mrt[0], mrt[1]].map(pct);
            let found = [
                cells[3],
                cells[4],
                cells[6],
                cells[8],
                cells[9],
                cells[10].trim_end_matches(" |"),
            ];
            assert_eq!(found, expected.each_ref().map(|s| s.as_str()), "{row}");
        }
    }

    /// SMALL_SPHERE_DRAG_CALIBRATED holds the runs of the report's table of the same spheres drawn
    /// larger by the radius correction.
    #[test]
    fn the_calibrated_small_sphere_drag_is_the_reports() {
        let section =
            crate::validate::report_section("## Immersed moving boundary: spheres of a few cells and less");
        let table = section
            .split("drawn larger by (tau 0.6 / 1, cells)")
            .nth(1)
            .expect("the table");
        for (d, [tau_06, tau_1]) in SMALL_SPHERE_DRAG_CALIBRATED {
            let row = table
                .lines()
                .find(|l| l.starts_with(&format!("| {d:.1} |")))
                .unwrap_or_else(|| panic!("no row for {d} cells"));
            let cells: Vec<&str> = row.split(" | ").collect();
            assert_eq!(
                [cells[2], cells[3].trim_end_matches(" |")],
                [format!("{tau_06:+.1}%"), format!("{tau_1:+.1}%")]
                    .each_ref()
                    .map(|s| s.as_str()),
                "{row}"
            );
        }
    }
}

//! `lbm-server bench --particles`: the coupled sweep's tables, which the GPU batch
//! (validation/gpu/run.sh) and validation/imb/seed_density.py read, on a small grid.

mod common;
use common::*;
use std::process::Command;

/// The rows of the markdown table that follows the line starting with `title`, as cells.
fn table(text: &str, title: &str) -> Vec<Vec<String>> {
    let lines = text.lines().skip_while(|l| !l.starts_with(title));
    lines
        .skip(3)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            l.split('|')
                .map(|c| c.trim().to_string())
                .filter(|c| !c.is_empty())
                .collect()
        })
        .collect()
}

fn percent(cell: &str) -> f64 {
    cell.trim_end_matches('%')
        .parse()
        .unwrap_or_else(|_| panic!("not a percentage: {cell}"))
}

fn number(cell: &str) -> f64 {
    cell.parse().unwrap_or_else(|_| panic!("not a number: {cell}"))
}

#[test]
fn the_coupled_bench_times_each_way_by_the_wall_clock_and_beside_lbm_only_steps_by_cpu_time() {
    let output = Command::new(bin("lbm-server"))
        .args([
            "bench",
            "--grid",
            "16x16x32",
            "--operator",
            "trt",
            "--particles",
            "8",
            "--steps",
            "4",
        ])
        .args(["--rounds", "1", "--covered-cells", "all", "--reference", "none"])
        .env("NODEVICE_SELECT", "1")
        .output()
        .expect("lbm-server bench");
    let text = output_text(&output);
    assert!(output.status.success(), "bench failed:\n{text}");

    let wall = table(&text, "coupled (spheres");
    let cpu = table(&text, "coupled steps by CPU time");
    let ways = |rows: &[Vec<String>]| -> Vec<(String, String)> {
        rows.iter().map(|r| (r[0].clone(), r[1].clone())).collect()
    };
    let mut expected = vec![(
        "0 (no coupling: one submit and wait per step)".to_string(),
        "-".to_string(),
    )];
    for way in ["fused", "skip"] {
        let what = format!("0 ({way} fluid kernels, no particle: one submit and wait per step)");
        expected.push((what, way.to_string()));
    }
    for count in ["8"] {
        for way in ["redo", "fused", "skip"] {
            expected.push((count.to_string(), way.to_string()));
        }
    }
    assert_eq!(ways(&wall), expected, "the wall-clock table:\n{text}");
    assert_eq!(ways(&cpu), expected, "the table by CPU time:\n{text}");

    for row in &wall {
        assert!(
            number(&row[2]) > 0.0 && percent(&row[3]) > 0.0,
            "{row:?}:\n{text}"
        );
    }
    // The LBM-only lockstep row is its own reference; each other row's ratio is the LBM-only
    // steps' CPU time beside it over its own.
    assert_eq!(cpu[0][2], cpu[0][3], "{text}");
    for row in &cpu {
        let (steps, beside) = (number(&row[2]), number(&row[3]));
        assert!(steps > 0.0 && beside > 0.0, "{row:?}:\n{text}");
        let ratio = 100.0 * beside / steps;
        assert!(
            (percent(&row[4]) - ratio).abs() <= 1.0,
            "{row:?}: ratio {ratio:.1}%:\n{text}"
        );
    }
}

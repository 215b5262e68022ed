//! `lbm-server bench --particles`: the coupled sweep's tables, which the GPU batch
//! (validation/gpu/run.sh, its coupled_rows.py) and validation/imb/seed_density.py read, on a
//! small grid.

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

/// The rows that validation/gpu/SCRIPT prints from the bench output `text` (saved as `name`, as
/// the GPU batch names it), and all it printed.
fn script_rows(script: &str, name: &str, text: &str) -> (Vec<Vec<String>>, String) {
    let file = temp_dir(script).join(name);
    std::fs::write(&file, text).unwrap();
    let script = format!("{}/validation/gpu/{script}", env!("CARGO_MANIFEST_DIR"));
    let output = Command::new("python3")
        .args([&script, file.to_str().unwrap(), "--print"])
        .output()
        .expect("python3");
    let printed = output_text(&output);
    assert!(output.status.success(), "{script} failed:\n{printed}");
    (table(&format!("title\n{printed}"), "title"), printed)
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
    // steps' CPU time beside it over its own: within what the printed times allow (two decimals,
    // a ms or less a step on this grid) and the ratio's own rounding to a percent.
    assert_eq!(cpu[0][2], cpu[0][3], "{text}");
    for row in &cpu {
        let (steps, beside) = (number(&row[2]), number(&row[3]));
        assert!(steps > 0.0 && beside > 0.0, "{row:?}:\n{text}");
        let low = 100.0 * (beside - 0.005) / (steps + 0.005) - 0.5;
        let high = 100.0 * (beside + 0.005) / (steps - 0.005) + 0.5;
        assert!(
            (low..=high).contains(&percent(&row[4])),
            "{row:?}: the ratio of these times lies in {low:.1}-{high:.1}%:\n{text}"
        );
    }
    batch_rows(&text, &wall);
}

/// validation/gpu/coupled_rows.py (which folds a GPU batch's sweeps into BENCHMARKS.md) on the
/// bench's output: a row for no particle and one for the 8 spheres, each way's MLUPS and ratio as
/// the bench printed them, the fastest in bold.
fn batch_rows(text: &str, wall: &[Vec<String>]) {
    let (rows, printed) = script_rows("coupled_rows.py", "coupled_trt.txt", text);
    assert_eq!(rows.len(), 2, "{printed}");
    let figure = |r: &Vec<String>| format!("{} ({})", r[2], r[3]);
    let eight: Vec<String> = wall.iter().filter(|r| r[0] == "8").map(figure).collect();
    let cells: Vec<String> = rows[1][4..7]
        .iter()
        .map(|c| c.trim_matches('*').to_string())
        .collect();
    assert_eq!(rows[1][2], "8", "{printed}");
    assert_eq!(cells, eight, "{printed}");
    // The fastest way in bold (each tied for it).
    let mlups = |c: &str| number(&c.trim_matches('*').split(' ').next().unwrap().replace(',', ""));
    for row in &rows {
        let ways: Vec<&String> = row[4..7].iter().filter(|c| *c != "-").collect();
        let best = ways.iter().map(|c| mlups(c)).fold(0.0, f64::max);
        for c in ways {
            assert_eq!(
                c.starts_with("**"),
                mlups(c) == best,
                "the fastest in bold: {row:?}"
            );
        }
    }
}

#[test]
fn the_kernel_bench_gives_validation_gpu_kernel_rows_each_storage_and_kernel() {
    let output = Command::new(bin("lbm-server"))
        .args([
            "bench",
            "--grid",
            "16x16x16",
            "--operator",
            "bgk",
            "--steps",
            "2",
            "--rounds",
            "1",
        ])
        .args(["--per-cell", "--storage", "fp32,fp16s"])
        .env("NODEVICE_SELECT", "1")
        .output()
        .expect("lbm-server bench");
    let text = output_text(&output);
    assert!(output.status.success(), "bench failed:\n{text}");
    let (rows, printed) = script_rows("kernel_rows.py", "bench_kernels.txt", &text);
    // What the bench printed of each storage and kernel, e.g. "storage fp16s  cells 1.6 MLUPS".
    let mlups = |storage: &str, kernel: &str| -> String {
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("storage {storage} ")) && l.contains(&format!(" {kernel} ")))
            .unwrap_or_else(|| panic!("no {storage} {kernel} line:\n{text}"));
        let words: Vec<&str> = line.split_whitespace().collect();
        words[3].to_string()
    };
    let storages: Vec<&str> = rows.iter().map(|r| r[3].as_str()).collect();
    assert_eq!(storages, ["FP32", "FP16S"], "{printed}");
    for (row, storage) in rows.iter().zip(["fp32", "fp16s"]) {
        assert_eq!(row[4], mlups(storage, "quads"), "{printed}\n{text}");
        assert_eq!(row[5], mlups(storage, "cells"), "{printed}\n{text}");
    }
}

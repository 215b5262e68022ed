//! The report `lbm-server validate` writes: its title, each section replaced in place under its
//! `## ` heading, and (for the tests) the sections and rows of validation/lbm/REPORT.md.

use crate::lbm::gpu::Gpu;
use std::path::Path;

/// The report as it starts: the existing one at `path` where only some sections are run (the
/// others kept as they are), else (or where there is none to read) the title, with the adapter
/// the cases ran on.
pub(super) fn start(path: &Path, only_some: bool, gpu: &Gpu) -> String {
    let title = format!(
        "# Lattice-Boltzmann core: validation report\n\nWritten by `lbm-server validate` on {} ({:?}).\n\
         All quantities in lattice units. Errors are relative L2 norms against the analytic solution.\n",
        gpu.adapter.name, gpu.adapter.backend
    );
    if !only_some {
        return title;
    }
    match std::fs::read_to_string(path) {
        Ok(existing) => existing,
        Err(e) => {
            protocol::say!(
                "lbm-server: {}: {e}; writing the chosen sections only",
                path.display()
            );
            title
        }
    }
}

/// `report` with the section of the same `## ` heading as `section` replaced by it (appended when
/// the report has no such section). A section runs from its heading to the next `## ` heading.
pub(super) fn replace_section(report: &str, section: &str) -> String {
    let heading = section.lines().find(|l| l.starts_with("## ")).unwrap_or_default();
    let marker = format!("\n{heading}\n");
    match report.find(&marker) {
        Some(start) if !heading.is_empty() => {
            let end = report[start + 1..]
                .find("\n## ")
                .map_or(report.len(), |k| start + 1 + k);
            format!("{}{section}{}", &report[..start], &report[end..])
        }
        _ => format!("{report}{section}"),
    }
}

/// The section of validation/lbm/REPORT.md under `heading` ("## ..."), up to the next heading.
#[cfg(test)]
pub(crate) fn report_section(heading: &str) -> &'static str {
    include_str!("../../../validation/lbm/REPORT.md")
        .split(heading)
        .nth(1)
        .and_then(|rest| rest.split("\n## ").next())
        .unwrap_or_else(|| panic!("the report has no section {heading:?}"))
}

/// The first `columns` cells ("| a | b") of the rows of the report's section `heading` whose
/// first cell starts with one of `starts`: the runs a section test holds against its constants.
#[cfg(test)]
pub(crate) fn report_rows(heading: &str, starts: &[&str], columns: usize) -> Vec<String> {
    report_section(heading)
        .lines()
        .filter(|l| starts.iter().any(|s| l.starts_with(&format!("| {s}"))))
        .map(|l| l.split(" | ").take(columns).collect::<Vec<_>>().join(" | "))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::replace_section;

    #[test]
    fn a_section_is_replaced_in_place_and_a_new_one_appended() {
        let report = "# R\n\n## A\n\nold a\n\n## B\n\nb\n";
        let replaced = replace_section(report, "\n## A\n\nnew a\n");
        assert_eq!(replaced, "# R\n\n## A\n\nnew a\n\n## B\n\nb\n");
        let last = replace_section(report, "\n## B\n\nnew b\n");
        assert_eq!(last, "# R\n\n## A\n\nold a\n\n## B\n\nnew b\n");
        let added = replace_section(report, "\n## C\n\nc\n");
        assert_eq!(added, format!("{report}\n## C\n\nc\n"));
    }
}

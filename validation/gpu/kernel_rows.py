"""The kernels' rows of a GPU batch (validation/gpu/run.sh: bench_kernels.txt, bench_trt.txt,
bench_mrt.txt) as a Markdown table, folded into BENCHMARKS.md between its markers
<!-- gpu-kernels:begin --> and <!-- gpu-kernels:end --> (import.sh calls it).

    python3 validation/gpu/kernel_rows.py DIR [--benchmarks BENCHMARKS.md]   # DIR: the batch's gpu/
    python3 validation/gpu/kernel_rows.py FILE.txt --print                  # one bench output, printed

Each row: the device, grid, operator and storage; the quads' and the per-cell kernel's MLUPS (best
round) and their ratio; the naive two-lattice kernel (FP32, BGK) and the copy bandwidth of the same
run; the per-cell kernel against the naive one.
"""

import re

import folding

BEGIN = "<!-- gpu-kernels:begin -->"
END = "<!-- gpu-kernels:end -->"
HEAD = (
    "| device | grid | operator | storage | quads MLUPS | per-cell MLUPS | per-cell / quads "
    "| naive MLUPS (same run) | per-cell / naive | copy bandwidth | file |\n"
    "|---|---|---|---|---:|---:|---:|---:|---:|---:|---|"
)


def number(pattern, text):
    m = re.search(pattern, text, re.M)
    return float(m.group(1)) if m else None


def rows(path):
    """The table's rows of one bench output (none when it has no per-cell figure)."""
    text = path.read_text(errors="replace")
    adapter = re.search(r"^adapter:\s+(.*) \(\w+, \w+\)\s*$", text, re.M)
    grid = re.search(r"^grid:\s+(\S+) .*operator (\w+)", text, re.M)
    if not adapter or not grid:
        return []
    device, (grid_text, operator) = adapter.group(1), grid.groups()
    naive = number(r"^naive kernel:\s+([\d.]+) MLUPS", text)
    copy = number(r"^copy bandwidth:\s+([\d.]+) GB/s", text)
    found = {}
    for storage, kernel, mlups in re.findall(r"^storage (\w+)\s+(quads|cells)\s+([\d.]+) MLUPS", text, re.M):
        found.setdefault(storage, {})[kernel] = float(mlups)
    if not found:
        quads = number(r"^MLUPS:\s+([\d.]+)", text)
        cells = number(r"^per cell:\s+([\d.]+) MLUPS", text)
        if quads is None or cells is None:
            return []
        found["fp32"] = {"quads": quads, "cells": cells}

    def fmt(x, spec="{:,.1f}"):
        return "-" if x is None else spec.format(x)

    out = []
    for storage, k in found.items():
        quads, cells = k.get("quads"), k.get("cells")
        ratio = cells / quads if quads and cells else None
        against_naive = cells / naive if naive and cells else None
        out.append(
            f"| {device} | {cube(grid_text)} | {operator.upper()} | {storage.upper()} "
            f"| {fmt(quads)} | {fmt(cells)} | {fmt(ratio, '{:.2f}x')} | {fmt(naive)} "
            f"| {fmt(against_naive, '{:.2f}x')} | {fmt(copy, '{:.1f} GB/s')} | `{path.name}` |"
        )
    return out


def cube(grid_text):
    """256x256x256 as 256^3 where the edges agree."""
    edges = grid_text.split("x")
    return f"{edges[0]}^3" if len(set(edges)) == 1 else " x ".join(edges)


if __name__ == "__main__":
    folding.main(__doc__, [f"bench_{name}" for name in ("kernels", "trt", "mrt")], rows, HEAD, (BEGIN, END))

"""The coupled sweeps of a GPU batch (validation/gpu/run.sh: coupled_trt.txt, coupled_seed_density.txt,
coupled_dense.txt, coupled_dem.txt, coupled_atomic_list.txt; each an `lbm-server bench --particles`
output) as a Markdown table, folded into BENCHMARKS.md between its markers
<!-- gpu-coupled:begin --> and <!-- gpu-coupled:end --> (import.sh calls it).

    python3 validation/gpu/coupled_rows.py DIR [--benchmarks BENCHMARKS.md]   # DIR: the batch's gpu/
    python3 validation/gpu/coupled_rows.py FILE.txt --print                  # one bench output, printed

Each row: the device, grid, particle count and the run's LBM-only MLUPS; for each way of treating
the covered cells (redo, fused, skip) the coupled MLUPS and its ratio to LBM-only, the fastest in
bold; the file it came from. The rows with no particle (the lockstep alone, and the fused and skip
fluid kernels with no particle) come first, as "0".
"""

import re

import folding

BEGIN = "<!-- gpu-coupled:begin -->"
END = "<!-- gpu-coupled:end -->"
FILES = ("coupled_trt", "coupled_seed_density", "coupled_dense", "coupled_dem", "coupled_atomic_list")
WAYS = ("redo", "fused", "skip")
HEAD = (
    "| device | grid | particles | LBM-only MLUPS | redo MLUPS (ratio) | fused MLUPS (ratio) "
    "| skip MLUPS (ratio) | file |\n"
    "|---|---|---:|---:|---:|---:|---:|---|"
)


def sweep(text):
    """{particles: {way: (MLUPS, ratio %)}} of the sweep's wall-clock table, and its LBM-only MLUPS;
    the rows with no particle under "0" (the lockstep alone as the way "-")."""
    head = re.search(r"^\| particles \| covered cells \| MLUPS \| ratio to LBM-only \(([\d.]+) MLUPS\) \|$", text, re.M)
    if not head:
        return None, {}
    found = {}
    for line in text[head.end():].splitlines()[2:]:
        cells = [c.strip() for c in line.split("|")[1:-1]]
        if len(cells) != 4:
            break
        particles = "0" if cells[0].startswith("0 ") else cells[0]
        found.setdefault(particles, {})[cells[1]] = (float(cells[2]), float(cells[3].rstrip("%")))
    return float(head.group(1)), found


def rows(path):
    """The table's rows of one bench output (none without a coupled sweep)."""
    text = path.read_text(errors="replace")
    adapter = re.search(r"^adapter:\s+(.*) \(\w+, \w+\)\s*$", text, re.M)
    grid = re.search(r"^grid:\s+(\S+) ", text, re.M)
    lbm_only, found = sweep(text)
    if not adapter or not grid or not found:
        return []
    out = []
    for particles, ways in found.items():
        best = max((m for w, (m, _) in ways.items() if w in WAYS), default=None)

        def cell(way):
            if way not in ways:
                return "-"
            mlups, ratio = ways[way]
            figure = f"{mlups:,.1f} ({ratio:.0f}%)"
            return f"**{figure}**" if mlups == best and len(ways) > 1 else figure

        count = particles if particles == "0" else f"{int(particles):,}"
        if "-" in ways:
            count = "0 (the ways' fluid kernels alone; LBM-only in lockstep {:,.1f}, {:.0f}%)".format(*ways["-"])
        out.append(
            f"| {adapter.group(1)} | {grid.group(1)} | {count} | {lbm_only:,.1f} "
            f"| {cell('redo')} | {cell('fused')} | {cell('skip')} | `{path.name}` |"
        )
    return out


if __name__ == "__main__":
    folding.main(__doc__, FILES, rows, HEAD, (BEGIN, END))

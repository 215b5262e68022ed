#!/usr/bin/env python3
"""The coupled step at the seed's particle density, pass by pass, for one or more lbm-server builds
run in alternation (BENCHMARKS.md, "The coupled step at the seed's density, by pass").

One sphere of 4 cells per 1024 cells: 512 spheres on 64 x 64 x 128, TRT. Each round runs
`lbm-server bench --passes --covered-cells all` once per build, the builds alternating, and
reads the CPU time of the process (all threads) per pass, each pass submitted and waited for on
its own: on a shared machine the CPU time moves far less than the wall time. Printed per build
and way: the median and range over the rounds of each pass, and three ratios to LBM-only:
"by CPU" is the LBM-only kernels' time (the redo's "fluid" pass of the same run: the fluid-only
step's kernels) over the way's whole step, each pass with a submit and wait of its own; "paired"
is by CPU time too, of whole steps as a run makes them, each way's steps in blocks alternating
with as many LBM-only steps (the bench's table by CPU time); "bench" is the bench's own wall-clock
ratio (its LBM-only rounds and coupled steps at different moments: on a loaded machine it moves by
2x).

    cargo build --release -p lbm-server
    cp target/release/lbm-server /tmp/after   # and a build of another commit as /tmp/before
    python3 validation/imb/seed_density.py --rounds 4 /tmp/before /tmp/after
"""
import argparse
import json
import os
import re
import statistics
import subprocess

BENCH = ["bench", "--grid", "64x64x128", "--operator", "trt", "--particles", "512", "--steps", "30",
         "--rounds", "1", "--passes", "--covered-cells", "all", "--reference", "none"]
WAYS = ["redo", "fused", "skip"]


def run(binary):
    """One bench run: {way: {pass: CPU ms}}, {way: {"bench": ratio %, "paired": ratio %}}, the
    load average before it."""
    load = open("/proc/loadavg").read().split()[0]
    env = dict(os.environ, NODEVICE_SELECT="1")
    out = subprocess.run(["nice", "-n", "5", binary] + BENCH, env=env, capture_output=True,
                         text=True, check=True).stdout.splitlines()
    passes, ratios = {}, {}
    for i, line in enumerate(out):
        cells = [c.strip() for c in line.split("|")[1:-1]]
        # The wall-clock table has 4 columns, the table by CPU time (paired) 5.
        table = {4: "bench", 5: "paired"}.get(len(cells))
        if table and cells[0] == "512" and cells[1] in WAYS:
            ratios.setdefault(cells[1], {})[table] = float(cells[-1].rstrip("%"))
        m = re.match(r"coupled step by pass, covered cells (\w+), CPU", line)
        if m:
            names = [c.strip() for c in out[i + 1].split("|")[2:-1]]
            values = [float(c) for c in out[i + 3].split("|")[2:-1]]
            passes[m.group(1)] = dict(zip(names, values))
    return passes, ratios, float(load)


def spread(values, digits=2):
    """median (low-high)"""
    return f"{statistics.median(values):.{digits}f} ({min(values):.{digits}f}-{max(values):.{digits}f})"


def report(binary, runs):
    loads = [r[2] for r in runs]
    print(f"\n{binary}: {len(runs)} rounds, load average {min(loads):.1f}-{max(loads):.1f}")
    lbm_only = [r[0]["redo"]["fluid"] for r in runs]
    for way in WAYS:
        names = list(runs[0][0][way])
        print(f"\n| {way}, CPU ms per step | " + " | ".join(names) + " |")
        print("|---|" + "---:|" * len(names))
        print("| median (range) | " + " | ".join(
            spread([r[0][way][n] for r in runs]) for n in names) + " |")
        by_cpu = [100 * lbm / r[0][way]["total"] for lbm, r in zip(lbm_only, runs)]
        bench = [r[1][way]["bench"] for r in runs]
        paired = [r[1][way]["paired"] for r in runs]
        print(f"\n{way}: coupling (all but fluid) {spread([r[0][way]['total without fluid'] for r in runs])} ms; "
              f"ratio to LBM-only by CPU {spread(by_cpu, 0)}%, paired {spread(paired, 0)}%, "
              f"bench {spread(bench, 0)}%")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("binaries", nargs="+", help="lbm-server builds, run in alternation")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    runs = {b: [] for b in args.binaries}
    for k in range(args.rounds):
        for b in args.binaries:
            runs[b].append(run(b))
            print(f"round {k + 1}: {b}: {json.dumps(runs[b][-1])}", flush=True)
    for b in args.binaries:
        report(b, runs[b])


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Cross-DEM coupled validation: the same scene with the built-in DEM, YADE and LIGGGHTS.

    python3 validation/crossdem/crossdem.py [--cases e1,default,shear] [--dems builtin,yade,liggghts]
                                            [--steps N] [--out DIR] [--server PATH] [--reuse]

Each case runs `lbm-server run SCENE --dem DEM` once per DEM (YADE's python finds iceoryx2 in
target/yade-py, as .ci/run installs it), reads OUT/particles.csv and compares one number:

| Case | Scene | Number |
|---|---|---|
| e1 | validation/scenes/ten-cate-e1.toml (6 cells per diameter) | peak settling speed |
| default | validation/scenes/default.toml (27 beads onto the floor and each other) | final mean height |
| shear | validation/crossdem/shear.toml (a sphere in a Couette flow) | final spin about y |

Writes DIR/results.json and, without --steps, validation/crossdem/results.json (the numbers, each DEM's difference from the built-in DEM, wall times) and
validation/crossdem/crossdem.png (the three cases, the three DEMs); REPORT.md quotes them. A DEM
that cannot run here (not installed) is left out with the reason.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
SCENES = {
    "e1": ROOT / "validation/scenes/ten-cate-e1.toml",
    "default": ROOT / "validation/scenes/default.toml",
    "shear": HERE / "shear.toml",
}
WHAT = {"e1": "peak settling speed [m/s]", "default": "final mean height [m]",
        "shear": "final spin about y [rad/s]"}
DEMS = ("builtin", "yade", "liggghts")


def run(server: str, case: str, dem: str, out: Path, steps) -> dict:
    """One coupled run; its wall time, exit status and the tail of its output."""
    cmd = [server, "run", str(SCENES[case]), "--dem", dem, "--out", str(out)]
    if steps:
        cmd += ["--steps", str(steps)]
    env = dict(os.environ, NODEVICE_SELECT="1")
    iox = ROOT / "target/yade-py"
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(iox), env.get("PYTHONPATH")) if p)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    cmd[2] = str(SCENES[case].relative_to(ROOT))
    return {"command": " ".join(cmd[1:]), "status": p.returncode,
            "wall_s": round(time.perf_counter() - t0, 1),
            "said": (p.stdout + p.stderr).strip().splitlines()[-3:]}


def reused(server: str, case: str, dem: str, out: Path) -> dict:
    """A run of an earlier call (--reuse), as its summary.json records it."""
    s = json.loads((out / "summary.json").read_text())
    return {"command": f"run {SCENES[case].relative_to(ROOT)} --dem {dem} --out {out}",
            "status": 0 if s["exit_reason"] == "completed" else 1,
            "wall_s": round(s["wall_time_s"], 1), "said": [s["exit_reason"]]}


def timing(out: Path) -> dict:
    """The server's lockstep wall time per fluid step and the shares of its parts."""
    s = json.loads((out / "summary.json").read_text())
    wall, steps = s["wall_time_s"], s["steps_completed"]
    return {"steps": steps, "ms_per_step": round(1e3 * wall / steps, 2),
            "share": {k: round(v / wall, 3) for k, v in s["time_s"].items()}}


def series(out: Path) -> dict:
    """Per output step: time, mean height, peak settling speed, mean spin about y."""
    rows = list(csv.DictReader(open(out / "particles.csv")))
    by_step = {}
    for r in rows:
        by_step.setdefault(int(r["step"]), []).append(r)
    t, z, vz, wy = [], [], [], []
    for step in sorted(by_step):
        rs = by_step[step]
        t.append(float(rs[0]["time"]))
        z.append(sum(float(r["z"]) for r in rs) / len(rs))
        vz.append(max(-float(r["vz"]) for r in rs))
        wy.append(sum(float(r["wy"]) for r in rs) / len(rs))
    return {"t": t, "z": z, "vz": vz, "wy": wy}


def measure(case: str, s: dict) -> float:
    if case == "e1":
        return max(s["vz"])
    if case == "default":
        return s["z"][-1]
    return s["wy"][-1]


def available(dem: str) -> str:
    """'' where the DEM can run here, else why not."""
    if dem == "liggghts":
        p = subprocess.run([sys.executable, str(ROOT / "clients/liggghts/lbm_liggghts.py"),
                            "--probe"], capture_output=True, text=True,
                           env=dict(os.environ, PYTHONPATH=str(ROOT / "clients/python")))
        return "" if p.returncode == 0 else p.stderr.strip()
    if dem == "yade":
        if not Path("/usr/bin/yade").exists():
            return "yade is not installed (sh validation/dem/install.sh)"
        if not (ROOT / "target/yade-py/iceoryx2").exists():
            return ("iceoryx2 for Debian's python is not in target/yade-py (/usr/bin/python3 -m "
                    "pip install --target target/yade-py iceoryx2==0.10.0)")
    return ""


def chart(results: dict, curves: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    style = {"builtin": ("k", "-", "built-in DEM"), "yade": ("tab:blue", "--", "YADE"),
             "liggghts": ("tab:red", ":", "LIGGGHTS")}
    panels = [("e1", "vz", "Ten Cate E1: settling speed [m/s]"),
              ("default", "z", "default scene: mean height [mm]"),
              ("shear", "wy", "sphere in shear: spin about y [rad/s]")]
    for ax, (case, key, title) in zip(axes, panels):
        for dem, s in curves.get(case, {}).items():
            colour, dash, label = style[dem]
            y = [1e3 * v for v in s[key]] if key == "z" else s[key]
            d = results[case][dem].get("vs_builtin")
            ax.plot(s["t"], y, color=colour, linestyle=dash, lw=1.6,
                    label=label + (f" ({100 * d:+.2g}%)" if d is not None and dem != "builtin" else ""))
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default="e1,default,shear")
    ap.add_argument("--dems", default=",".join(DEMS))
    ap.add_argument("--steps", type=int, help="cut every run to N steps")
    ap.add_argument("--out", default=str(ROOT / "out/crossdem"))
    ap.add_argument("--server", default=str(ROOT / "target/debug/lbm-server"))
    ap.add_argument("--chart", default=str(HERE / "crossdem.png"))
    ap.add_argument("--reuse", action="store_true",
                    help="take the runs whose OUT/CASE-DEM/summary.json exists from there")
    args = ap.parse_args(argv)
    out = Path(args.out)
    results, curves = {}, {}
    for case in args.cases.split(","):
        results[case], curves[case] = {"what": WHAT[case]}, {}
        for dem in args.dems.split(","):
            why = available(dem)
            if why:
                results[case][dem] = {"skipped": why}
                print(f"{case} {dem}: skipped: {why}", flush=True)
                continue
            done = out / f"{case}-{dem}" / "summary.json"
            if args.reuse and done.exists():
                r = reused(args.server, case, dem, out / f"{case}-{dem}")
            else:
                r = run(args.server, case, dem, out / f"{case}-{dem}", args.steps)
            if r["status"] == 0:
                curves[case][dem] = series(out / f"{case}-{dem}")
                r["value"] = measure(case, curves[case][dem])
                r.update(timing(out / f"{case}-{dem}"))
                del r["said"]
            results[case][dem] = r
            print(f"{case} {dem}: {r.get('value')} ({r['wall_s']} s, exit {r['status']})",
                  flush=True)
        base = results[case].get("builtin", {}).get("value")
        for dem in DEMS:
            v = results[case].get(dem, {}).get("value")
            if base and v is not None:
                results[case][dem]["vs_builtin"] = v / base - 1.0
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    if not args.steps:  # the report's runs, not a cut one
        (HERE / "results.json").write_text(json.dumps(results, indent=1))
    chart(results, curves, Path(args.chart))
    print(f"results: {out / 'results.json'}; chart: {args.chart}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Running the Ten Cate scenes, for validation/imb/ten_cate.py.

`lbm-server run` on a scene, what a run keeps in its work folder (scene.toml, summary.json, log.txt,
load.txt, the sphere's rows of particles.csv: reduce_csv), the missing runs made and distilled into
the results (run_one), and a GPU batch's run folders taken into the work folder (import_runs).
"""
import csv
import os
import shutil
import subprocess
import time

from ten_cate_analysis import distil, records
from ten_cate_scenes import MACH, OPERATOR, ROOT, RUNS, run_dir, write_scene


# LBM_SERVER: another lbm-server (with its dem-client beside it), e.g. a copy that a rebuild of
# target/ during a long run cannot replace.
BINARY = os.environ.get("LBM_SERVER", os.path.join(ROOT, "target", "release", "lbm-server"))


def reduce_csv(src, dst, keep=("step", "time", "x", "y", "z", "vx", "vy", "vz", "fz"), digits=7, row_kept=None):
    """The sphere's rows (id 0) of particles.csv, columns `keep`, `digits` significant digits; with
    `row_kept`, only the rows it accepts."""
    with open(src) as f, open(dst, "w", newline="") as g:
        r = csv.DictReader(f)
        w = csv.writer(g)
        w.writerow(keep)
        for row in r:
            if row["id"] != "0" or (row_kept and not row_kept(row)):
                continue
            w.writerow([row["step"]] + ["%.*g" % (digits, float(row[k])) for k in keep[1:]])


def uptime():
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "?"


def run_scene(out, text):
    """Writes the scene TEXT to OUT/scene.toml and runs it into OUT/work, its output in
    OUT/log.txt; (exit code, OUT/work)."""
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "scene.toml")
    with open(path, "w") as f:
        f.write(text)
    work = os.path.join(out, "work")
    with open(os.path.join(out, "log.txt"), "w") as log:
        code = subprocess.call([BINARY, "run", path, "--out", work], stderr=log, stdout=log)
    return code, work


def run_one(case, n, force=False, mach=MACH, op=OPERATOR, width=None, height=None, sim_time=None, explicit=False,
            out=None):
    """Runs (case, n) into `out` (default: its folder in the work folder RUNS, then distilled into the
    results), unless the folder has a summary.json or the results a record of it."""
    folder = out or run_dir(case, n, mach, op, width, height, explicit)
    done = os.path.exists(os.path.join(folder, "summary.json")) or (not out and os.path.basename(folder) in records())
    if done and not force:
        print("%s N=%g: already run (%s), skipped" % (case, n, folder))
        return
    run_into(folder, case, n, mach, op, width, height, sim_time, explicit)
    if not out:
        distil([folder])


def run_into(out, case, n, mach=MACH, op=OPERATOR, width=None, height=None, sim_time=None, explicit=False,
             storage=None):
    """Writes (case, n)'s scene into OUT (with lattice.storage = `storage` where given), runs it there and
    keeps its summary.json, log.txt, load.txt and the sphere's rows of particles.csv."""
    os.makedirs(out, exist_ok=True)
    scene = os.path.join(out, "scene.toml")
    ln = write_scene(case, n, scene, mach, op, width, height, sim_time, explicit, storage)
    print("%s N=%g %s: %d x %d x %d cells, dx %.4g m, dt %.4g s, tau %.4f (predicted), %d steps, %.3g s simulated"
          % (case, n, op, *ln["cells"], ln["dx"], ln["dt"], ln["tau"], ln["steps"], ln["steps"] * ln["dt"]), flush=True)
    if ln["tau"] < 0.5005:
        print("  tau %.5f < 0.5005: skipped" % ln["tau"])
        return
    tmp = os.path.join("/tmp", "ten_cate_" + os.path.basename(out))
    shutil.rmtree(tmp, ignore_errors=True)
    env = dict(os.environ, NODEVICE_SELECT="1")
    load = ["before: " + uptime()]
    t0 = time.time()
    with open(os.path.join(out, "log.txt"), "w") as log:
        p = subprocess.run([BINARY, "run", scene, "--out", tmp], stdout=log, stderr=subprocess.STDOUT, env=env, cwd=ROOT)
    wall = time.time() - t0
    load.append("after:  " + uptime())
    with open(os.path.join(out, "load.txt"), "w") as f:   # the machine's load around the run (shared cores)
        f.write("\n".join(load) + "\n")
    print("  exit %d after %.1f s" % (p.returncode, wall), flush=True)
    if os.path.exists(os.path.join(tmp, "summary.json")):
        shutil.copy(os.path.join(tmp, "summary.json"), os.path.join(out, "summary.json"))
    if os.path.exists(os.path.join(tmp, "particles.csv")):
        reduce_csv(os.path.join(tmp, "particles.csv"), os.path.join(out, "particles.csv"))
    shutil.rmtree(tmp, ignore_errors=True)   # drops fields/ (.vti) and the full csv


def import_runs(src, force=False, runs=RUNS, prefix=""):
    """Each DIR/<prefix><name>/ that holds a summary.json goes to RUNS/<name>/ (the work folder) as `run_one`
    leaves its runs: scene.toml, summary.json, log.txt and the sphere's rows of particles.csv. A run already
    there is kept unless `force`. Returns the folders imported."""
    done = []
    for name in sorted(os.listdir(src)):
        d = os.path.join(src, name)
        if not name.startswith(prefix) or not os.path.exists(os.path.join(d, "summary.json")):
            print("%s: no summary.json, not imported" % name)
            continue
        out = os.path.join(runs, name[len(prefix):])
        if os.path.exists(os.path.join(out, "summary.json")) and not force:
            print("%s: already in %s, kept (--force replaces it)" % (name, out))
            continue
        os.makedirs(out, exist_ok=True)
        for f in ("scene.toml", "summary.json", "log.txt"):
            if os.path.exists(os.path.join(d, f)):
                shutil.copy(os.path.join(d, f), os.path.join(out, f))
        if os.path.exists(os.path.join(d, "particles.csv")):
            reduce_csv(os.path.join(d, "particles.csv"), os.path.join(out, "particles.csv"))
        print("%s: imported into %s" % (name, out))
        done.append(out)
    return done


def run_folders(folder):
    """The run folders in FOLDER (those with a summary.json), sorted."""
    return [os.path.join(folder, name) for name in sorted(os.listdir(folder))
            if os.path.exists(os.path.join(folder, name, "summary.json"))]

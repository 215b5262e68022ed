"""Running the fluidized bed's scenes, for validation/imb/fluidized_bed.py.

A case or the held bed run into its folder of the work folder validation/imb/work/fluidized_bed/,
what that folder keeps of the run (keep: exit code, summary.json, heights.csv, grains.csv), then
distilled into the results; a GPU batch's runs taken in the same way (import_runs).
"""
import os
import shutil

import results as compact  # validation/imb/results.py: the work folder
import ten_cate_runs  # validation/imb/ten_cate.py's parts: lbm-server, LBM_SERVER and how a scene is run
from fluidized_bed_analysis import distil, heights
from fluidized_bed_scenes import CELLS, HELD_FROM, SCRIPT, held_name, held_scene_text, name, scene_text


OUT = compact.work(SCRIPT)


def keep(out, work, code):
    """What the work folder keeps of a run whose outputs are in WORK: its exit code, summary.json, the
    grains' mean height and the liquid's force on them per row (heights.csv) and where the grains
    were in the last row (grains.csv, what `held` holds)."""
    with open(os.path.join(out, "exit_code"), "w") as f:
        f.write("%d\n" % code)
    if os.path.exists(os.path.join(work, "summary.json")):
        shutil.copy(os.path.join(work, "summary.json"), os.path.join(out, "summary.json"))
    particles = os.path.join(work, "particles.csv")
    if os.path.exists(particles):
        rows, last = heights(particles)
        with open(os.path.join(out, "heights.csv"), "w") as f:
            f.write("time,mean_height,grains,in_band,at_top,fluid_fz\n")
            for t, h, n, b, top, fz in rows:
                f.write("%.6g,%.6g,%d,%d,%d,%.6g\n" % (t, h, n, b, top, fz))
        with open(os.path.join(out, "grains.csv"), "w") as f:
            f.write("x,y,z\n")
            for p in last:
                f.write("%.8g,%.8g,%.8g\n" % tuple(p))


def run_held(cells, operator=HELD_FROM[0]):
    out = os.path.join(OUT, held_name(cells, operator))
    code, work = ten_cate_runs.run_scene(out, held_scene_text(cells, operator))
    keep(out, work, code)
    shutil.rmtree(work, ignore_errors=True)
    distil([out])


def run(operator, re_, depth, cells=CELLS):
    out = os.path.join(OUT, name(operator, re_, depth, cells))
    code, work = ten_cate_runs.run_scene(out, scene_text(operator, re_, depth, cells))
    keep(out, work, code)
    shutil.rmtree(work, ignore_errors=True)
    distil([out])


def import_runs(folder):
    """FOLDER/bed_<name>/ of a GPU batch (scene.toml, log.txt, exit_code, summary.json,
    particles.csv) into the work folder as `run` leaves its runs, then into the results."""
    done = []
    for entry in sorted(os.listdir(folder)):
        src = os.path.join(folder, entry)
        if not entry.startswith("bed_") or not os.path.exists(os.path.join(src, "exit_code")):
            print("%s: no exit_code (not run), not imported" % entry)
            continue
        out = os.path.join(OUT, entry[len("bed_"):])
        os.makedirs(out, exist_ok=True)
        for f in ("scene.toml", "log.txt"):
            shutil.copy(os.path.join(src, f), os.path.join(out, f))
        keep(out, src, int(open(os.path.join(src, "exit_code")).read()))
        print("%s: imported into %s" % (entry, out))
        done.append(out)
    distil(done)

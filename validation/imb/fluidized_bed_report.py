"""validation/imb/FLUIDIZED_BED.md, written by `python3 validation/imb/fluidized_bed.py --report`.

From the records alone: the table of the cases (outcome, voidage against Richardson & Zaki and
Tenneti et al., the weight the liquid carries), the held bed's table (held_rows), the summary's
rows with the command of each, and the text around them (report).
"""
import math
import os

import results as compact  # validation/imb/results.py: the records and the report's opening summary
from fluidized_bed_references import buoyant_weight, richardson_zaki, settling_reynolds, tenneti, tenneti_voidage
from fluidized_bed_scenes import (AVERAGE_FROM, CASES, D, GPU_CASES, GPU_HELD_CELLS, HELD_AVERAGE_FROM, HELD_CELLS,
                                  HELD_DENSITY, HELD_FROM, HELD_GAP, HELD_SUPERPOSED_CELLS, HELD_TIME, HERE, NU,
                                  SCRIPT, SIM_TIME, SPEED_OVER_U, held_name, inflow, label, lattice_tau, name, periodic)


REPORT = os.path.join(HERE, "FLUIDIZED_BED.md")


# The command that makes a case's run on a GPU (the batch of validation/gpu/: prepare.sh writes the
# scenes, run.sh runs them on the device machine, import.sh takes them into the results).
GPU_BATCH = "bash validation/gpu/prepare.sh"


def held_rows(opening):
    """The held bed's report lines; its rows of the summary appended to OPENING."""
    operator, re_, depth, _ = HELD_FROM
    lines = held_header(operator, re_)
    runs = [(cells, operator) for cells in HELD_CELLS + GPU_HELD_CELLS] + [(cells, "mrts") for cells in HELD_SUPERPOSED_CELLS]
    records = compact.runs(SCRIPT)
    for cells, held_operator in runs:
        rec = records.get(held_name(cells, held_operator))
        if rec is None:
            continue
        lines.append(held_row(rec, cells, held_operator, opening))
    return lines


def held_header(operator, re_):
    """The held bed's heading, description and table header."""
    return [
        "",
        "## The bed held still",
        "",
        "The grains where the %s Re %d run left them (its last row, in the record of %s, pushed apart"
        % (label(operator), re_, name(*HELD_FROM)),
        "to %g um where they touched) held in place (no gravity and density %g kg/m^3 in the scene), the"
        % (HELD_GAP * 1e6, HELD_DENSITY),
        "same inflow (Re %d), %.2f s; the liquid's vertical force on all of them over their buoyant weight," % (re_, HELD_TIME),
        "mean and range from %.2f s on (the free bed's own, from %.2f s, in the table above: the liquid" % (HELD_AVERAGE_FROM, AVERAGE_FROM),
        "carries the weight of a fluidized bed). Reference: Tenneti, Garg & Subramaniam (2011), fixed",
        "random arrays resolved (solid fraction 0.1-0.5, Re up to 300), at the held bed's voidage (from",
        "its grains' mean height, as above) and Re %d; Richardson & Zaki's bed at that voidage stands at" % re_,
        "the Re given. Largest displacement: how far a held grain moved over the run.",
        "",
        "| cells per d | tau | solid term | outcome | steps | wall time [s] | MLUPS | device | force / buoyant weight (range) | Tenneti | error | voidage | Richardson-Zaki Re | largest displacement [cells] |",
        "|---:|---:|---|---|---:|---:|---:|---|---|---:|---:|---:|---:|---:|",
    ]


def held_row(rec, cells, held_operator, opening):
    """The held bed's row of the run REC at CELLS per diameter; its row of the summary appended to OPENING."""
    operator, re_, depth, _ = HELD_FROM
    ar, re_t = settling_reynolds()
    done, columns = run_columns(rec)
    eps = rec["start_voidage"]
    expected = 3.0 * math.pi * re_ * tenneti(1.0 - eps, re_) / (ar * math.pi / 6.0)
    n_rz, _, _ = richardson_zaki(re_, depth)
    re_rz = re_t * eps**n_rz
    force = error = moved = ""
    if "force_over_buoyant_weight" in rec:
        mean = rec["force_over_buoyant_weight"][0]
        force = "%.3f (%.3f-%.3f)" % tuple(rec["force_over_buoyant_weight"])
        error = "%+.0f%%" % (100.0 * (mean / expected - 1.0))
    if "largest_displacement_m" in rec:
        moved = "%.2g" % (rec["largest_displacement_m"] / (D / cells))
    command = GPU_BATCH if cells in GPU_HELD_CELLS else \
        "python3 validation/imb/fluidized_bed.py %s" % ("held-superposed" if held_operator == "mrts" else "held")
    opening.append(("held bed, %d cells per d, %s term: liquid's force / buoyant weight" % (
        cells, "superposition" if held_operator == "mrts" else "Noble-Torczynski"),
        "%.3f, Tenneti et al. (2011)" % expected, force.split(" ")[0] or columns[0],
        error.replace("%", " %") or "-", command))
    return (
        "| %d | %.4f | %s | %s | %s | %s | %s | %s | %s | %.3f | %s | %.3f | %.0f | %s |"
        % (
            cells,
            lattice_tau(re_, cells),
            "superposition" if held_operator == "mrts" else "Noble-Torczynski",
            *columns,
            force,
            expected,
            error,
            eps,
            re_rz,
            moved,
        )
    )


def run_columns(rec):
    """(ran to the end, the report's outcome, steps, wall time, MLUPS and device columns) of a run's record."""
    done, reason, steps, wall, mlups = (rec[k] for k in ("ran_to_end", "reason", "steps", "wall_time_s", "fluid_mlups"))
    text = "ran %.2f s" % rec["simulated_s"] if done else reason.replace("|", "/")
    return done, [
        text,
        steps if steps is not None else "",
        "%.0f" % wall if wall else "",
        "%.2f" % mlups if mlups else "",
        rec["device"],
    ]


def report():
    """Writes FLUIDIZED_BED.md from the records, and prints it."""
    lines = introduction()
    records = compact.runs(SCRIPT)
    opening = []
    for operator, re_, depth, cells in CASES + GPU_CASES:
        rec = records.get(name(operator, re_, depth, cells))
        if rec is None:
            continue
        lines.append(case_row(rec, (operator, re_, depth, cells), opening))
    lines.append("")
    lines += FINDINGS
    lines += held_rows(opening)
    lines[2:2] = [compact.summary(opening, "python3 validation/imb/fluidized_bed.py --report",
                                  "`%s` writes the scenes of the GPU batch (validation/gpu/)." % GPU_BATCH), ""]
    with open(REPORT, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def introduction():
    """The heading, the scene, how voidage and weight are measured, and the table header."""
    ar, re_t = settling_reynolds()
    return [
        "# A fluidized bed at Re 200 and 400 by operator (the seed paper's section 5)",
        "",
        "Written by `python3 validation/imb/fluidized_bed.py --report` from `results/fluidized_bed.json`",
        "(runs on lavapipe, this repository's 2-core CPU machine, shared with other runs: read wall time and",
        "MLUPS as +-50%; the device column names the others). The scene:",
        "validation/scenes/fluidized-bed.toml, 216 sand grains (d = 3 mm, density ratio 2.65) in",
        "water-like liquid (nu = %.3g m^2/s), a slab 10 x 4 x 24 diameters (60 x 24 x 144 cells; one case" % NU,
        "8 diameters deep with 504 grains, 7 rows across; five with periodic sides, one of them 8 deep, one with walls frictionless for the grains), 6 cells per diameter (9 and 12; 10 and 15 on a GPU:",
        "the device column), uniform inflow through the floor at U = Re nu / d, a pressure",
        "outlet at the top (the equilibrium outflow, docs/lbm.md), DEM planes 2.5 diameters from both.",
        "Each case runs %.2f s; lattice.velocity_scale is %.2f U (the liquid between the grains), Mach" % (SIM_TIME, SPEED_OVER_U),
        "0.1, so tau = 0.5017 at Re 400 and 0.5034 at Re 200 (tau - 1/2 grows as the cells per diameter).",
        "The seed's bed (BGK, 10 cells per diameter)",
        "ran at Re 200 and diverged at Re 400.",
        "",
        "Voidage: the grains' centres average h above the distributor, a uniform bed is 2h high, voidage",
        "= 1 - N V_p / (A 2h), averaged over the rows from %.2f s on (mean and range); \"1-3 d\": the" % AVERAGE_FROM,
        "grains whose centres lie 1 to 3 diameters above the distributor, over that band's volume. Reference:",
        "Richardson & Zaki (1954), U / u_i = eps^n, with the grain's settling velocity from",
        "Schiller-Naumann (Archimedes number %.3g: Re_t = %.0f, u_t = %.3f m/s) and n from Rowe" % (ar, re_t, re_t * NU / D),
        "(1987); \"walled\" divides u_t by 10^(d/D) with D the slab's 4 diameters (Richardson & Zaki's",
        "wall term, made for tubes: for a slab it is an estimate). \"Grains at the top\": centres within a",
        "diameter of the top plane in the last row kept (a bed lifted against it is no longer fluidized).",
        "\"Weight the liquid carries\": its vertical force on the grains (buoyancy included) over their",
        "weight, mean of the rows from %.2f s on (1: the bed is fluidized, not resting on the planes)." % AVERAGE_FROM,
        "\"Tenneti\": the voidage at which Tenneti, Garg & Subramaniam's (2011) fixed random arrays carry",
        "a grain's buoyant weight at that Re; \"drag / Tenneti's\": the liquid's force on the grains over",
        "what their law gives at the measured voidage and Re (validation/lbm/REPORT.md's random arrays at",
        "voidage 0.76: 1.6-1.8 at 6-12 cells per diameter). \"Periodic sides\": the slab's four side",
        "faces periodic for the liquid and the grains, no side walls or planes.",
        "",
        "| case | Re | slab depth [d] | cells per d | tau | U [m/s] | outcome | steps | wall time [s] | MLUPS | device | grains at the top, last row | weight the liquid carries | voidage (range) | voidage 1-3 d (range) | Richardson-Zaki | walled | error | Tenneti | drag / Tenneti's |",
        "|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---|---|---:|---|---|---:|---:|---:|---:|---:|",
    ]


def case_row(rec, case, opening):
    """The table row of the run REC of CASE (operator, Re, depth, cells); its row of the summary appended to OPENING."""
    operator, re_, depth, cells = case
    done, columns = run_columns(rec)
    n, eps_rz, eps_walled = richardson_zaki(re_, depth)
    measured = band = error = top = carried = excess = ""
    if "last_row" in rec:
        top = "%s of %s (%.2f s)" % (rec["last_row"]["at_top"], rec["last_row"]["grains"], rec["last_row"]["time"])
    if "voidage" in rec:
        mean = rec["voidage"][0]
        measured = "%.3f (%.3f-%.3f)" % tuple(rec["voidage"])
        error = "%+.1f%%" % (100.0 * (mean / eps_rz - 1.0))
        band = "%.3f (%.3f-%.3f)" % tuple(rec["band_voidage"])
        if "weight_carried" in rec:
            share = rec["weight_carried"]
            carried = "%.3f" % share
            excess = "%.2f" % (share * buoyant_weight(re_) / tenneti(1.0 - mean, re_))
    gpu = (operator, re_, depth, cells) in GPU_CASES
    opening.append(("%s, Re %d, slab %d d, %d cells per d: bed voidage" % (label(operator), re_, depth, cells),
                    "%.3f, Richardson-Zaki" % eps_rz, measured.split(" ")[0] or columns[0],
                    error.replace("%", " %") or "-",
                    GPU_BATCH if gpu else "python3 validation/imb/fluidized_bed.py %s" % name(operator, re_, depth, cells)))
    return (
        "| %s | %d | %d | %d | %.4f | %.4f | %s | %s | %s | %s | %s | %s | %s | %s | %s | %.3f | %s | %s | %.3f | %s |"
        % (
            label(operator),
            re_,
            depth,
            cells,
            lattice_tau(re_, cells),
            inflow(re_),
            *columns,
            top,
            carried,
            measured,
            band,
            eps_rz,
            "-" if periodic(operator) else "%.3f" % eps_walled,
            error,
            tenneti_voidage(re_),
            excess,
        )
    )


# What the runs found, below the table.
FINDINGS = [
    "Error: the measured voidage against Richardson-Zaki without the wall term. What these runs",
    "found (the ramp, the outflow without backflow, the bed lifted at Re 400, BGK and TRT with",
    "tau- <= 1 blowing up in the bed where they held one sphere): docs/imb.md, \"Stability near",
    "tau = 1/2\". BGK was refused below tau 0.51 until 2026-12-03. The liquid carries the bed's",
    "weight: it is fluidized, its grains feel too much drag. The grid hardly changes that: MRT at",
    "Re 200 expands the bed to voidage 0.761, 0.757 and 0.747 at 6, 10 and 15 cells per diameter",
    "(+30.1%, +29.4%, +27.8%; 10 and 15 on an NVIDIA H200, 2026-12-04), and at 10 cells Re 400",
    "lifts the bed against the top plane and blows up (step 11293, 0.65 s) and BGK at Re 200 blows",
    "up (step 1534) as at 6. Held still (below) the grains carry their buoyant weight at 6, 9 and 12",
    "cells alike (1.07, 1.05, 1.01): not their motion, and not the grid. With the superposition",
    "solid term (\"MRT, superposition\", coupling.solid_collision; docs/imb.md \"The solid",
    "collision\"), which drags every sphere 10-20% less, the bed at 6 cells expands 16.2% more than",
    "Richardson & Zaki instead of 30.1%, and held it carries 0.77 of its weight instead of 1.07;",
    "but that term also drags 9-15% too little in Stokes flow, where the default is within 1%.",
    "A simple cubic array at",
    "voidage 0.76 carries the weight at Re 476-491 at 6 to 24 cells (spheres in line shelter each",
    "other); a random array in a periodic box at Re 252-266 at 6 to 12 cells, where Tenneti et al.'s",
    "random arrays need 361, though in Stokes flow it converges to theirs, and at 279 at 18 cells (one",
    "placement): its excess falls with the grid, as a lone sphere's at Re 200-300 does, +25-29% above",
    "Schiller & Naumann at 6 cells, +6-7% at 16 (validation/lbm/REPORT.md, \"drag in a bed\", \"a random",
    "array at the fluidized bed's voidage\" and \"a held sphere at the fluidized bed's Reynolds",
    "numbers\"; docs/imb.md).",
    "Without the side walls (\"MRT, periodic sides\": the slab's four side faces periodic for the",
    "liquid and the grains, 2026-12-05) the bed at Re 200 expands to voidage 0.709 / 0.718 / 0.719 at",
    "6 / 9 / 12 cells (+21.2 / +22.7 / +23.0%), its grains dragged 1.84 / 1.94 / 1.96 times Tenneti et",
    "al.'s at that voidage, where the walled slab's are 2.48 at 6 cells (2.55 twice as deep, 2.29 at",
    "15): about a third of the excess expansion is the walls' (Richardson & Zaki's wall term, made for",
    "tubes, expects more of them), the rest the drag that the random arrays show at these grids, 1.6-1.8",
    "times Tenneti's, not falling from 6 to 12 cells (1.5 at 18 cells). Which walls: periodic along y",
    "only (\"MRT, periodic along y\", the walls 10 diameters apart kept, those 4 apart gone) the bed",
    "expands to 0.733 at 6 cells (+25.3%, drag 2.11 times Tenneti's): each pair of walls makes about",
    "half of the walls' share. Twice as deep and periodic along y, 0.732 (+25.2%): the pair 8",
    "diameters apart adds 6.2 points (31.4 - 25.2), the pair 4 apart 4.8, the pair 10 apart 4.1; a pair",
    "of walls adds 4-6 points whatever its distance, not a confinement that falls as 1/width. Nor is it",
    "a circulation the walls drive: both beds circulate (grains' vz from 0.4 s on, by distance from the",
    "x faces, a throwaway rerun: walled, -4 to -8 mm/s within 3 d of the walls, +12 mm/s beyond 4 d;",
    "periodic, -9 to -16 mm/s within 3 d of the faces, +17 mm/s beyond), the periodic one no less. Nor",
    "is it the grains rubbing on",
    "the walls: with the walls frictionless for them (\"MRT, walls frictionless\") the bed expands to",
    "0.761 at 6 cells (+30.2%), as with friction. The periodic slab at 15 cells is in the GPU batch.",
]

#!/usr/bin/env python3
"""The summary that opens validation/lbm/REPORT.md, rebuilt from the report's own sections.

`lbm-server validate --only NAME` replaces its section of REPORT.md in place and keeps the others,
this one ("## Summary", before the first section) included; `lbm-server validate` without --only
writes the report anew, without it. Either way this script takes the figures of the sections' tables
(one or a few rows per section: its finest grid, or the range over a series) and writes the summary
table again: case, reference, measured, error, and the command that regenerates the section.

    python3 validation/lbm/summary.py            # rewrite the summary of validation/lbm/REPORT.md
    python3 validation/lbm/summary.py --check    # exit 1 if the summary is not what the sections give
"""
import os
import sys

REPORT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "REPORT.md")
HEADING = "## Summary"
NOTE = ("One or a few rows per section below, taken from its table by `python3 validation/lbm/summary.py`, which "
        "rebuilds this table after `lbm-server validate` (that replaces the sections it runs and keeps this one; "
        "run without --only it writes the report anew). The command of a row regenerates its section.")


def sections(text):
    """(the text before the first section, [(heading, body)] of the "## " sections)."""
    parts = text.split("\n## ")
    return parts[0], [("## " + p.split("\n", 1)[0], p.split("\n", 1)[1] if "\n" in p else "") for p in parts[1:]]


def tables(body):
    """The markdown tables of a section's BODY, each a list of rows {column header: cell}."""
    out, lines = [], body.split("\n")
    for k in range(len(lines) - 1):
        if lines[k].startswith("|") and lines[k + 1].startswith("|---") and (k == 0 or not lines[k - 1].startswith("|")):
            header = cells(lines[k])
            rows = []
            for line in lines[k + 2:]:
                if not line.startswith("|"):
                    break
                rows.append(dict(zip(header, cells(line))))
            out.append(rows)
    return out


def cells(line):
    return [c.strip() for c in line.strip()[1:-1].split("|")]


def num(cell):
    return float(cell.rstrip("%"))


def span(values, fmt="%s"):
    """"a to b" of the VALUES (cells) by number, or the one value."""
    lo, hi = min(values, key=num), max(values, key=num)
    return fmt % lo if lo == hi else "%s to %s" % (fmt % lo, fmt % hi)


def groups(rows, *keys):
    """ROWS grouped by the columns KEYS, in order of first appearance."""
    out = {}
    for r in rows:
        out.setdefault(tuple(r[k] for k in keys), []).append(r)
    return out.items()


def channel(t):
    out = []
    for rows, flow in zip(t, ("between plates", "in a square duct")):
        r = [r for r in rows if r["observed order"] and num(r["observed order"]) >= 1.5][-1]
        out.append(("Poiseuille %s, BGK, tau %s, %s cells across" % (flow, r["tau"], r["cells across"]),
                    "analytic profile: second order", "observed order %s" % r["observed order"],
                    "L2 %s" % r["L2 error"]))
    return out


def wall(t):
    taus = [r["tau"] for r in t[0]]
    return [("Poiseuille between plates, 16 cells, %s, tau %s-%s: the wall's place" % (op, taus[0], taus[-1]),
             "analytic profile, walls half-way", "velocity profile", "L2 %s" % span([r["%s L2 error" % op] for r in t[0]]))
            for op in ("TRT", "BGK")]


def taylor_green(t):
    return [("Taylor-Green decay, 32 x 32, %s, tau 0.8" % r["operator"], "nu %s" % r["nu expected"],
             "nu %s" % r["nu measured"], r["relative error"]) for r in t[0]]


def mass(t):
    r = t[0][0]
    return [("closed 16^3 box, moving lid, TRT, 10,000 steps", "mass %s before" % r["mass before"],
             "mass %s after" % r["mass after"], r["relative drift"])]


def array_drag(t):
    finest = max(num(r["box n"]) for r in t[0])
    return [("simple cubic array, solid fraction %s, box %s (radius %s cells), TRT tau 1" % (
        r["solid fraction"], r["box n"], r["radius (cells)"]), "K %s, Zick & Homsy" % r["K Zick-Homsy"],
        "K %s" % r["K measured"], r["error"]) for r in t[0] if num(r["box n"]) == finest]


def sphere_drag(t):
    out = []
    for (re_,), rows in groups(t[0], "Re"):
        r = ([r for r in rows if r["W"].startswith("W ->")] or rows)[-1]
        out.append(("sphere held in a stream, Re %s, %s cells per d, W %s" % (re_, r["d"], r["W"].replace("W ", "")),
                    "C_d %s, Schiller & Naumann" % r["C_d Schiller-Naumann"], "C_d %s" % r["C_d measured"], r["error"]))
    return out


def momentum(t):
    r = t[0][0]
    return [("free sphere in a periodic 16^3 box, 300 steps", "momentum %s" % r["initial"],
             "momentum %s" % r["after 300 steps"], r["relative change"])]


def over_tau(t, measured, error):
    """Per box and operator, the range over tau of the column MEASURED (K) and of ERROR."""
    return [("Zick-Homsy array 0.125, box %s (radius %s cells), %s, tau %s-%s" % (
        box, rows[0][[k for k in rows[0] if k.endswith("radius (cells)")][0]], op, rows[0]["tau"], rows[-1]["tau"]),
        "K %s, Zick & Homsy" % rows[0]["K Zick-Homsy"], "K %s" % span([r[measured] for r in rows]),
        span([r[error] for r in rows])) for (box, op), rows in groups(t[0], "box n", "operator")]


def drag_tau(t):
    return over_tau(t, "K", "error")


def radius_deficit(t):
    return [(case.replace("array 0.125", "array 0.125 drawn larger by its deficit"), ref, measured, error)
            for case, ref, measured, error in over_tau(t, "K drawn + delta", "error drawn")]


def sphere_correction(t):
    finest = max(num(r["d"]) for r in t[0])
    return [("held sphere, Re 32.2, %s cells per d, W %s, L %s, tau %s, drawn larger by %s cells" % (
        r["d"], r["W"], r["L"], r["tau"], r["drawn larger by"]), "C_d %s, Schiller & Naumann" % r["C_d Schiller-Naumann"],
        "C_d %s" % r["C_d"], r["error"]) for r in t[0] if num(r["d"]) == finest]


def moving_boundary(t):
    e4 = [r for r in t[0] if r["Re"] == "32.2"]
    out = [("towed against held, Re 32.2, 6 cells per d, %s, %s weighting" % (op, w), "the held sphere's C_d %s" % span(
        [r["held C_d"] for r in rows]), "C_d %s (towed, 12-14 d)" % span([r["towed C_d 12-14 d"] for r in rows]),
        span([r["towed against held"] for r in rows])) for (op, w), rows in groups(e4, "operator", "weighting")]
    moving = [r for r in t[1] if num(r["velocity"]) > 0]
    out += [("Zick-Homsy array moving at 0.03-0.06 cells per step, %s, tau %s" % (op, span([r["tau"] for r in rows])),
             "the array at rest", "K %s" % span([r["K"] for r in rows]), span([r["against the array at rest"] for r in rows]))
            for (op,), rows in groups(moving, "operator")]
    return out


def stability(t):
    out = []
    for (faces,), rows in groups(t[0], "faces"):
        held = {}
        for (op,), runs in groups(rows, "operator"):
            held[op] = max([num(r["Re"]) for r in runs if r["outcome"] == "held"], default=None)
        out.append(("a held sphere's wake, 8 cells per d, %s faces: the highest Re held" % faces,
                    "the seed's BGK bed (10 cells per d) held Re 200, diverged at 400",
                    "; ".join("%s %s" % (op, "none" if re_ is None else "%g" % re_) for op, re_ in held.items()), "-"))
    return out


def wake_drag(t):
    mrt = [r for r in t[0] if r["operator"] == "MRT" and r["weighting"] == "Noble-Torczynski" and r["u0"] == "0.08"]
    out = []
    for (re_,), rows in groups(mrt, "Re"):
        r = max(rows, key=lambda r: num(r["d (cells)"]))
        out.append(("held sphere, Re %s, %s cells per d, MRT" % (re_, r["d (cells)"]),
                    "C_d %s, Schiller & Naumann" % r["C_d Schiller-Naumann"], "C_d %s" % r["C_d mean"], r["error"]))
    return out


def superposed_wake_drag(t):
    return [(case + ", superposition term", ref, measured, error) for case, ref, measured, error in wake_drag(t)]


def bed_drag(t):
    r = max(t[0], key=lambda r: num(r["box n"]))
    ref = num(r["Richardson-Zaki Re"])
    return [("simple cubic array carrying the bed's weight, solid fraction %s, %s cells per d" % (
        r["solid fraction"], r["d (cells)"]), "Re %s, Richardson & Zaki" % r["Richardson-Zaki Re"],
        "Re %s" % r["Re mean"], "%+.1f%%" % (100.0 * (num(r["Re mean"]) / ref - 1.0)))]


def random_drag(t, how=""):
    out = []
    for (flow, placement), rows in groups(t[0], "flow", "placement"):
        r = max(rows, key=lambda r: num(r["box n"]))
        out.append(("random array%s at solid fraction 0.24, %s, placement %s, %s cells per d" % (
            how, flow, placement, r["d (cells)"]), "Re %s, Tenneti et al." % r["Tenneti Re"], "Re %s" % r["Re mean"],
            r["error"]))
    return out


def staircase_drag(t):
    return random_drag(t, " of solid cells")


def solid_collision(t):
    return [("Zick-Homsy array %s, %s solid term, BGK/TRT/MRT, tau %s" % (phi, term, span([r["tau"] for r in rows])),
             "K %s, Zick & Homsy" % rows[0]["K Zick-Homsy"], "K %s" % span([r["K"] for r in rows]),
             span([r["error"] for r in rows])) for (phi, term), rows in groups(t[0], "solid fraction", "solid term")]


def unresolved_drag(t):
    ref = {r["diameter (cells)"]: r["K Sangani-Acrivos"] for r in t[0]}
    out = []
    for rows, column, how in ((t[0], "TRT 0.6 rest", "at rest"), (t[1], "TRT 0.6 moving", "moving, drawn larger (calibrated)")):
        for r in rows:
            d = r["diameter (cells)"]
            if d in ("2.0", "4.0", "6.0"):
                k = num(ref[d]) * (1.0 + num(r[column]) / 100.0)
                out.append(("sphere of %s cells, TRT tau 0.6, %s" % (d, how), "K %s, Sangani & Acrivos" % ref[d],
                            "K %.4f" % k, r[column]))
    return out


def storage(t):
    """The 16-bit storages against FP32: each case at its usual speed, the slowest lattice speed of each
    low-Mach series where both stay within 0.5% of FP32, and the mass drift of the longest run."""
    out = [("%s, FP16S and FP16C" % r["case"], "FP32: %s %s" % (r["quantity"], r["FP32"]),
            "FP16S %s, FP16C %s" % (r["FP16S"], r["FP16C"]),
            "%s, %s" % (r["FP16S against FP32"], r["FP16C against FP32"])) for r in t[0]]
    for series, rows in groups(t[1], "quantity"):
        for column in ("FP16S", "FP16C"):
            held = [r for r in rows if abs(num(r[column + " against FP32"])) <= 0.5]
            failed = [r for r in rows if abs(num(r[column + " against FP32"])) > 0.5]
            slowest = min(held, key=lambda r: num(r["lattice speed"])) if held else None
            out.append(("%s, %s, low Mach: the slowest lattice speed within 0.5%% of FP32" % (
                rows[0]["case"].split(",")[0], column), "FP32", "lattice speed %s" % (
                slowest["lattice speed"] if slowest else "none"),
                "%s at %s" % (failed[0][column + " against FP32"], failed[0]["lattice speed"]) if failed else "-"))
    r = t[2][-1]
    out.append(("closed 16^3 box, moving lid, TRT, %s steps, FP16S and FP16C" % r["steps"],
                "FP32 drift %s" % r["FP32 relative drift"], "drift %s, %s" % (
                    r["FP16S relative drift"], r["FP16C relative drift"]), "-"))
    return out


def storage_ten_cate(t):
    return [("Ten Cate E3, 9 cells per d, %s: terminal speed" % r["storage"], "FP32 run",
             "%s m/s" % r["terminal speed (m/s)"], r["terminal against FP32"])
            for r in t[0] if r["storage"] != "fp32"]


# The sections by the start of their heading: the name `lbm-server validate --only` runs them by (or
# the command that writes the section), and the rows of the summary their tables give.
SECTIONS = [
    ("## Poiseuille flow", "channel", channel),
    ("## Wall location", "wall", wall),
    ("## Taylor-Green", "taylor-green", taylor_green),
    ("## Mass conservation", "mass", mass),
    ("## Immersed moving boundary: drag of a simple cubic array", "array-drag", array_drag),
    ("## Immersed moving boundary: a sphere held in a uniform stream", "sphere-drag", sphere_drag),
    ("## Immersed moving boundary: momentum conservation", "momentum", momentum),
    ("## Immersed moving boundary: drag against tau", "drag-tau", drag_tau),
    ("## Immersed moving boundary: hydrodynamic radius deficit", "radius-deficit", radius_deficit),
    ("## Immersed moving boundary: the radius correction on a held sphere", "sphere-correction", sphere_correction),
    ("## Immersed moving boundary: the sphere at rest and moving", "moving-boundary", moving_boundary),
    ("## Stability near tau = 1/2", "stability", stability),
    ("## Immersed moving boundary: a held sphere at the fluidized bed's Reynolds numbers, the superposition term",
     "wake-drag-superposition", superposed_wake_drag),
    ("## Immersed moving boundary: a held sphere at the fluidized bed's Reynolds numbers", "wake-drag", wake_drag),
    ("## Immersed moving boundary: drag in a bed", "bed-drag", bed_drag),
    ("## Immersed moving boundary: a random array at the fluidized bed's voidage, as solid cells",
     "random-drag-staircase", staircase_drag),
    ("## Immersed moving boundary: a random array", "random-drag", random_drag),
    ("## Immersed moving boundary: the solid collision term", "array-drag-solid-collision", solid_collision),
    ("## Immersed moving boundary: spheres of a few cells", "unresolved-drag", unresolved_drag),
    ("## Storage of the populations: FP16S and FP16C", "storage", storage),
    ("## Storage of the populations: a settling sphere", "python3 validation/lbm/storage.py run", storage_ten_cate),
]


def summary(text):
    """The summary section ("## Summary" ...) that the sections of the report TEXT give."""
    _, parts = sections(text)
    lines = [HEADING, "", NOTE, "", "| case | reference | measured | error | command |", "|---|---|---|---|---|"]
    for heading, body in parts:
        spec = next((s for s in SECTIONS if heading.startswith(s[0])), None)
        if spec is None:
            continue
        for row in spec[2](tables(body)):
            command = spec[1] if " " in spec[1] else "lbm-server validate --only " + spec[1]
            lines.append("| %s | %s | %s | %s | `%s` |" % (*row, command))
    return "\n".join(lines) + "\n"


def with_summary(text):
    """TEXT with its summary section replaced (or put before the first section)."""
    head, parts = sections(text)
    new = summary(text)
    kept = "".join("\n" + h + "\n" + b for h, b in parts if h != HEADING)
    return head + "\n" + new + kept


def main():
    text = open(REPORT).read()
    updated = with_summary(text)
    if sys.argv[1:] == ["--check"]:
        sys.exit(0 if updated == text else "%s: the summary is not what the sections give: "
                 "python3 validation/lbm/summary.py" % REPORT)
    if sys.argv[1:]:
        sys.exit(__doc__)
    with open(REPORT, "w") as f:
        f.write(updated)


if __name__ == "__main__":
    main()

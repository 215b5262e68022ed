"""The charts of the Ten Cate report, for validation/imb/ten_cate.py, drawn from the records.

Settling speed and trajectory per case (velocity_E1.png ... velocity_E4.png), speed against
accuracy (speed_vs_accuracy.png), the larger boxes (wide_boxes.png) and the collision operators
(speed_vs_accuracy_operators.png), all in validation/imb/.
"""
import os

from ten_cate_analysis import box_baseline
from ten_cate_scenes import CASES, GAP0, HERE, OPERATOR, OPERATORS, op_name


COLORS = {"E1": "tab:blue", "E2": "tab:orange", "E3": "tab:green", "E4": "tab:red"}


def charts(results, extra=()):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    paths = []
    ok = [r for r in results if "peak_speed" in r]
    ns = sorted({r["N"] for r in ok})
    styles = ["-", "--", "-.", ":"]
    # velocity vs time, one chart per case, all resolutions
    for case in CASES:
        rs = sorted([r for r in ok if r["case"] == case], key=lambda r: r["N"])
        if not rs:
            continue
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
        for k, r in enumerate(rs):
            s = r["series"]
            a1.plot(s["t"], s["speed"], styles[k % 4], label="N = %g (dx %.3g mm)" % (r["N"], r["dx"] * 1e3))
            a2.plot(s["t"], [g * 1e3 for g in s["gap"]], styles[k % 4], label="N = %g" % r["N"])
        for e in [e for e in extra if e["case"] == case and "series" in e]:
            s = e["series"]
            a1.plot(s["t"], s["speed"], color="0.4", lw=1.0, label="N = %g, Mach %g (tau %.2f)" % (e["N"], e["mach"], e["tau"]))
            a2.plot(s["t"], [g * 1e3 for g in s["gap"]], color="0.4", lw=1.0, label="N = %g, Mach %g" % (e["N"], e["mach"]))
        a1.axhline(CASES[case]["u_inf"], color="k", lw=0.8, ls=":", label="u_inf (unbounded) %.3f m/s" % CASES[case]["u_inf"])
        a1.set_xlabel("time [s]"); a1.set_ylabel("settling speed -v_z [m/s]")
        a1.set_title("%s (Re %.1f): settling speed" % (case, CASES[case]["Re"]))
        a1.legend(fontsize=8); a1.grid(alpha=0.3)
        a2.set_xlabel("time [s]"); a2.set_ylabel("gap to the floor [mm]")
        a2.set_title("%s: trajectory (bottom of sphere)" % case)
        a2.legend(fontsize=8); a2.grid(alpha=0.3)
        fig.tight_layout()
        p = os.path.join(HERE, "velocity_%s.png" % case)
        fig.savefig(p, dpi=110); plt.close(fig)
        paths.append(p)
    # speed against accuracy
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    ax2 = ax.twinx()
    for case in CASES:
        rs = sorted([r for r in ok if r["case"] == case], key=lambda r: r["N"])
        if not rs:
            continue
        x = [r["N"] for r in rs]
        ax.plot(x, [abs(r["peak_error_pct"]) for r in rs], "o-", color=COLORS[case], label="%s |error| %%" % case)
        ax2.plot(x, [r["updates_per_sim_s"] / 1e9 for r in rs], "s--", color=COLORS[case], alpha=0.6,
                 label="%s G cell updates / sim s" % case)
    ax.axhline(3.0, color="k", lw=0.8, ls=":")
    ax.text(ns[0] if ns else 3, 3.2, "target 3 %", fontsize=8)
    ax.set_xlabel("cells per diameter N")
    ax.set_ylabel("|peak speed - u_inf| / u_inf  [%]  (solid)")
    ax.set_title("Speed against accuracy: the cost in cell updates, any device", fontsize=10)
    fig.text(0.01, 0.01, "wall s per simulated s = 1000 G / MLUPS. MLUPS: these runs 1-14 (lavapipe, 2 cores); "
             "whole Ten Cate runs on an NVIDIA H200 2,150-2,350", fontsize=7)
    ylabel = "G lattice cell updates per simulated second (dashed)"
    paths.append(finish_speed_chart(fig, ax, ax2, "upper right", "speed_vs_accuracy.png", ylabel))
    return paths


def finish_speed_chart(fig, ax, ax2, legend_at, name, ylabel="wall seconds per simulated second (dashed)"):
    """The cost axis, the joint legend and the file of a speed-against-accuracy chart; returns its path."""
    import matplotlib.pyplot as plt
    ax2.set_ylabel(ylabel)
    ax2.set_yscale("log")
    h1, l1 = ax.get_legend_handles_labels(); h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc=legend_at, ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    p = os.path.join(HERE, name)
    fig.savefig(p, dpi=110); plt.close(fig)
    return p


def wide_charts(wide, results, extra):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    paths = []
    cases = [c for c in CASES if any(r["case"] == c and "series" in r for r in wide)]
    if not cases:
        return paths
    fig, axes = plt.subplots(1, len(cases), figsize=(5.2 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        c = CASES[case]
        rs = [r for r in wide if r["case"] == case and "series" in r]
        bases = []
        for r in rs:
            b = box_baseline(r, results, extra)
            if b is not None and b not in bases:
                bases.append(b)
        for k, b in enumerate(sorted(bases, key=lambda b: b["N"])):
            s = b["series"]
            ax.plot([(GAP0 - g) * 1e3 for g in s["gap"]], [v / c["u_inf"] for v in s["speed"]], color=("0.55", "0.2")[k % 2], lw=1.0,
                    ls=(":", "--")[k % 2], label="N = %g, 100 x 100 x 160 mm (experiment)" % b["N"])
        for k, r in enumerate(rs):
            s = r["series"]
            ln = ax.plot([(r["release_gap"] - g) * 1e3 for g in s["gap"]], [v / c["u_inf"] for v in s["speed"]],
                         ["-", "--", "-.", ":"][k % 4], lw=1.3,
                         label="N = %g, %g x %g x %g mm" % (r["N"], r["box"][0] * 1e3, r["box"][1] * 1e3, r["box"][2] * 1e3))
            # the plateau window and its mean
            f0, f1 = r["release_gap"] - r["window_gap"][0], r["release_gap"] - r["window_gap"][1]
            ax.plot([f0 * 1e3, f1 * 1e3], [r["terminal_speed"] / c["u_inf"]] * 2, color=ln[0].get_color(), lw=4, alpha=0.35)
        ax.axhline(1.0, color="k", lw=0.8, ls=":")
        for y in (0.97, 1.03):
            ax.axhline(y, color="k", lw=0.5, ls="--", alpha=0.4)
        ax.set_ylim(0.7, 1.2)
        ax.set_xlabel("distance fallen [mm]")
        ax.set_ylabel("settling speed / u_inf (unbounded %.3f m/s)" % c["u_inf"])
        mach = sorted({r["mach"] for r in rs})
        ax.set_title("%s (Re %.1f), Mach %s: larger boxes" % (case, c["Re"], "/".join("%g" % m for m in mach)))
        ax.legend(fontsize=6.5, loc="lower center", ncol=2)
        ax.grid(alpha=0.3)
    fig.suptitle("Settling speed against distance fallen; thick bars: plateau window (speed within 0.5 % of its maximum) and its mean; dashed: +-3 %",
                 fontsize=8)
    fig.tight_layout()
    p = os.path.join(HERE, "wide_boxes.png")
    fig.savefig(p, dpi=110); plt.close(fig)
    paths.append(p)
    return paths


OP_COLORS = {"bgk": "tab:purple", "trt": "tab:green", "mrt": "tab:brown", "trts": "tab:olive"}


def op_chart(ops, results, case="E3"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    ax2 = ax.twinx()
    drawn = False
    for op in OPERATORS:
        src = [r for r in results if r["case"] == case] if op == OPERATOR else [r for r in ops if r["case"] == case and r["op"] == op]
        rs = sorted([r for r in src if "peak_speed" in r], key=lambda r: r["N"])
        if not rs:
            continue
        drawn = True
        x = [r["N"] for r in rs]
        ax.plot(x, [abs(r["peak_error_pct"]) for r in rs], "o-", color=OP_COLORS[op], label="%s |error| %%" % op_name(op))
        timed = rs
        if op == OPERATOR:    # TRT reruns (<case>_N<n>_trt) timed beside the BGK and MRT runs, where present
            rr = sorted([r for r in ops if r["case"] == case and r["op"] == op and "peak_speed" in r], key=lambda r: r["N"])
            timed = rr or rs
        ax2.plot([r["N"] for r in timed], [r["wall_s_per_sim_s"] for r in timed], "s--", color=OP_COLORS[op], alpha=0.7,
                 label="%s wall s / sim s%s" % (op_name(op), " (reruns)" if timed is not rs else ""))
    if not drawn:
        plt.close(fig)
        return []
    ax.axhline(3.0, color="k", lw=0.8, ls=":")
    ax.text(3, 3.2, "target 3 %", fontsize=8)
    ax.set_xlabel("cells per diameter N")
    ax.set_ylabel("|peak speed - u_inf| / u_inf  [%%]  (solid), %s" % case)
    ax.set_title("%s (Re %.1f), experiment's box, Mach 0.1: operators (lavapipe CPU, 2 shared cores)" % (case, CASES[case]["Re"]), fontsize=9)
    return [finish_speed_chart(fig, ax, ax2, "center right", "speed_vs_accuracy_operators.png")]

"""The conclusions of the Ten Cate report's larger-box runs, for validation/imb/ten_cate.py.

The headline's verdict against the target (3 % of u_inf), the findings per case and box
(conclusions), the widest boxes against the drag laws (law_check) and the tau check in a larger box
(tau_check_in_larger_boxes), with the fixed sentences they close on.
"""
from ten_cate_analysis import box_baseline, drag_law_velocity, find_run, widest
from ten_cate_scenes import CASES, op_name


def tau_check_in_larger_boxes(tau_wide, wide_main):
    """A finding per larger-box run at another Mach number: its terminal speed against the main
    run's in the same box at the same N."""
    out = ""
    for r in tau_wide:
        if "terminal_speed" not in r:
            continue
        m = find_run(wide_main, r["case"], r["N"], r["box"][0] * 1e3, r["box"][2] * 1e3)
        if not m or "terminal_speed" not in m:
            continue
        out += ("\n- **Tau check in a larger box:** %s at N = %g in %g x %g x %g mm: tau %.3f -> %.3f (Mach %g -> "
                "%g) moves the terminal speed from %s to %s of u_inf (%.4f -> %.4f m/s): the part of the excess that "
                "the boundary's tau dependence makes (validation/lbm/REPORT.md, \"drag against tau\"); what "
                "lowering tau leaves is the resolution's and the reference's (plateau windows of %d and %d rows: "
                "a window of a few rows is a noisy speed's maximum, not its mean)." % (
                    r["case"], r["N"], *(round(L * 1e3, 3) for L in r["box"]), m["tau"], r["tau"], m["mach"],
                    r["mach"], "%+.1f %%" % m["terminal_error_pct"], "%+.1f %%" % r["terminal_error_pct"], m["terminal_speed"],
                    r["terminal_speed"], m["window_rows"], r["window_rows"]))
    return out


def conclusions(results, extra, wide, opw=()):
    """The conclusions of the larger-box runs: (headline, "what the error means", wide-box findings)."""
    if not wide:
        return "", "", ""
    e4 = {k: find_run(wide, "E4", *k) for k in [(6, 100, 320), (6, 200, 320), (6, 300, 320), (6, 200, 240), (9, 200, 240),
                                                 (12, 200, 240), (12, 150, 240), (16, 150, 240)]}
    e1 = {k: find_run(wide, "E1", *k) for k in [(6, 100, 240), (6, 200, 240), (6, 300, 240), (9, 200, 240), (12, 200, 240)]}
    e2 = {k: find_run(wide, "E2", *k) for k in [(6, 200, 240), (9, 200, 240), (12, 200, 240)]}
    e3 = {k: find_run(wide, "E3", *k) for k in [(6, 200, 240), (9, 200, 240), (12, 200, 240), (6, 300, 320)]}
    b4 = box_baseline(e4[(6, 300, 320)], results, extra) if e4[(6, 300, 320)] else None
    b1 = box_baseline(e1[(6, 300, 240)], results, extra) if e1[(6, 300, 240)] else None
    head = box_headlines(e4, e1, e3, b4, b1)
    find = (e4_findings(e4, b4) + e1_findings(e1, b1) + e3_findings(e3, results, extra) + e2_findings(e2)
            + e4_n16_findings(e4, wide))
    allw = list(wide) + list(opw)
    badw = [r for r in allw if r.get("exit_code") != 0]
    find.append("- **Stability:** " + ("all %d runs in larger boxes completed (exit 0, no health-check failure)." % len(allw) if not badw
                else "runs that did not complete: " + ", ".join("%s (%s)" % (r["dir"], r.get("exit_reason")) for r in badw)))
    find.append(WIDE_END)
    verdict = widest_runs(wide)
    head.append(verdict_headline(verdict))
    laws = law_check(verdict)
    if laws:
        head.append(laws[0])
        find.append(laws[1])
    ops_w = operator_errors(wide, opw)
    if ops_w:
        head.append("**These larger-box numbers are TRT's (the operator of the main table); the operator matters:** in the same "
                    "200 x 200 x 240 mm box %s (section \"Operators\")." % "; ".join(ops_w))
    return " ".join(head), MEANING_END, "\n".join(f for f in find if f)


def terminal_error(r):
    return "%+.1f %%" % r["terminal_error_pct"]


def box_headlines(e4, e1, e3, b4, b1):
    """The headline's sentences on E4's and E1's wall effect and E3 in the larger box."""
    head = []
    if e4[(6, 300, 320)] and b4:
        w = e4[(6, 300, 320)]
        t = ("**E4's %+.1f %% in the experiment's box is half box, half simulation:** at N = 6 the box lowers the "
             "peak by a factor %.3f, and in the 300 mm wide box E4 settles %s from u_inf" % (
                 b4["peak_error_pct"], b4["peak_speed"] / w["terminal_speed"], terminal_error(w)))
        if e4[(9, 200, 240)] and e4[(6, 200, 240)]:
            t += (" (in 200 x 200 x 240 mm: %s at N = 6, %s at N = 9, so refining does not remove it)" % (
                terminal_error(e4[(6, 200, 240)]), terminal_error(e4[(9, 200, 240)])))
        head.append(t + ".")
    if e1[(6, 300, 240)] and b1:
        w = e1[(6, 300, 240)]
        t = ("**The experiment's walls hide a too-fast sphere at low Re:** E1 at N = 6 (Mach 0.05, tau 0.85) peaks "
             "%+.1f %% from u_inf in the experiment's box but settles %s from it in a 300 mm wide box (wall effect %.3f)" % (
                 b1["peak_error_pct"], terminal_error(w), b1["peak_speed"] / w["terminal_speed"]))
        if e1[(9, 200, 240)] and e1[(6, 200, 240)]:
            t += ("; in 200 x 200 x 240 mm it is %s at N = 6 and %s at N = 9 (tau %.2f)" % (
                terminal_error(e1[(6, 200, 240)]), terminal_error(e1[(9, 200, 240)]), e1[(9, 200, 240)]["tau"]))
        head.append(t + ".")
    if e3[(6, 200, 240)]:
        t = "E3 in 200 x 200 x 240 mm: %s at N = 6" % terminal_error(e3[(6, 200, 240)])
        if e3[(9, 200, 240)]:
            t += ", %s at N = 9" % terminal_error(e3[(9, 200, 240)])
        if e3[(12, 200, 240)]:
            t += ", %s at N = 12" % terminal_error(e3[(12, 200, 240)])
        if e3[(6, 300, 320)]:
            t += "; %s at N = 6 in 300 x 300 x 320 mm" % terminal_error(e3[(6, 300, 320)])
        head.append(t + ".")
    return head


def e4_findings(e4, b4):
    """Where E4's box effect comes from, and E4 by N (6, 9, 12) in the same box."""
    find = []
    if e4[(6, 100, 320)] and e4[(6, 300, 320)] and b4:
        tall, w = e4[(6, 100, 320)], e4[(6, 300, 320)]
        find.append(
            "- **Where E4's box effect comes from (N = 6):** the 100 x 100 x 320 mm box (the experiment's width, more "
            "than twice the fall) gives %.4f m/s against the peak %.4f m/s in the experiment's box: %.1f %% of u_inf "
            "is the short fall (E4, the highest Stokes number, approaches its plateau slowly, within 0.5 %% only after "
            "about 100 mm of fall, and in the 160 mm box the floor acts before that), %.1f %% the lateral walls (%.4f "
            "m/s at 300 mm). The same short-fall effect shows between the 240 and 320 mm tall boxes at 200 mm width "
            "(%.4f against %.4f m/s)." % (
                tall["terminal_speed"], b4["peak_speed"], 100 * (tall["terminal_speed"] - b4["peak_speed"]) / CASES["E4"]["u_inf"],
                100 * (w["terminal_speed"] - tall["terminal_speed"]) / CASES["E4"]["u_inf"], w["terminal_speed"],
                e4[(6, 200, 240)]["terminal_speed"] if e4[(6, 200, 240)] else float("nan"),
                e4[(6, 200, 320)]["terminal_speed"] if e4[(6, 200, 320)] else float("nan")))
    if e4[(9, 200, 240)] and e4[(6, 200, 240)]:
        a6, a9 = e4[(6, 200, 240)], e4[(9, 200, 240)]
        find.append(
            "- **E4 does not improve from N = 6 to 9:** in the same 200 x 200 x 240 mm box the terminal speed is %.4f "
            "m/s (%s) at N = 6 and %.4f m/s (%s) at N = 9, as in the experiment's box (-5.7 %% to -6.0 %% for N = 6-12). "
            "Applying the N = 6 width and height effect (300 x 300 x 320 against 200 x 200 x 240 mm: %+.1f %%) to "
            "N = 9 would put N = 9 near %+.1f %% (an estimate, not a run)." % (
                a6["terminal_speed"], terminal_error(a6), a9["terminal_speed"], terminal_error(a9),
                (e4[(6, 300, 320)]["terminal_error_pct"] - a6["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan"),
                (a9["terminal_error_pct"] + e4[(6, 300, 320)]["terminal_error_pct"] - a6["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan")))
    if e4[(12, 200, 240)] and e4[(9, 200, 240)] and e4[(6, 200, 240)]:
        find.append(
            "- **E4 at N = 12** (made last, with the current code: ramp solid fraction, sub-step drag), same "
            "200 x 200 x 240 mm box: %.4f m/s (%s), after %s at N = 6 and %s at N = 9: the deficit shrinks slowly "
            "with N; the N = 6 widening to 300 x 300 x 320 mm (%+.1f %%) would put it near %+.1f %% (an estimate, "
            "not a run)." % (
                e4[(12, 200, 240)]["terminal_speed"], terminal_error(e4[(12, 200, 240)]), terminal_error(e4[(6, 200, 240)]), terminal_error(e4[(9, 200, 240)]),
                (e4[(6, 300, 320)]["terminal_error_pct"] - e4[(6, 200, 240)]["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan"),
                (e4[(12, 200, 240)]["terminal_error_pct"] + e4[(6, 300, 320)]["terminal_error_pct"]
                 - e4[(6, 200, 240)]["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan")))
    return find


def e1_findings(e1, b1):
    """E1: the lateral walls and the broad plateau; E1 by N."""
    find = []
    if e1[(6, 100, 240)] and e1[(6, 300, 240)] and b1:
        n100, w2, w3 = e1[(6, 100, 240)], e1[(6, 200, 240)], e1[(6, 300, 240)]
        find.append(
            "- **E1 (Re 1.5): the lateral walls are everything, and the plateau is a broad maximum.** In the 100 mm "
            "wide box the height hardly matters (%.4f m/s in 240 mm, peak %.4f m/s in 160 mm); widening to 200 and "
            "300 mm raises the speed by %+.1f %% and then %+.1f %%. In the wide boxes the lid and the floor act over "
            "many diameters at this Reynolds number, so the speed stays within 0.5 %% of its maximum over only "
            "%.0f-%.0f mm of fall (%.0f mm in the 100 mm box, whose walls screen them). The 300 mm value is therefore "
            "a lower bound of E1's unbounded terminal velocity: a wider or taller box would most likely raise it further (not run)." % (
                n100["terminal_speed"], b1["peak_speed"],
                100 * (w2["terminal_speed"] - n100["terminal_speed"]) / n100["terminal_speed"] if w2 else float("nan"),
                100 * (w3["terminal_speed"] - w2["terminal_speed"]) / w2["terminal_speed"] if w2 else float("nan"),
                w3["window_fall"] * 1e3, w2["window_fall"] * 1e3 if w2 else float("nan"), n100["window_fall"] * 1e3))
    if e1[(9, 200, 240)] and e1[(6, 200, 240)]:
        a6, a9 = e1[(6, 200, 240)], e1[(9, 200, 240)]
        t = "- **E1 with N** (Mach 0.05; tau %.2f -> %.2f), 200 x 200 x 240 mm: %.4f m/s (%s) -> %.4f m/s (%s)" % (
            a6["tau"], a9["tau"], a6["terminal_speed"], terminal_error(a6), a9["terminal_speed"], terminal_error(a9))
        a12 = e1[(12, 200, 240)]
        if a12:
            t += " -> %.4f m/s (%s) at N = 12 (tau %.2f, above the 1.0 the coupled run warns about)" % (
                a12["terminal_speed"], terminal_error(a12), a12["tau"])
        find.append(t + ".")
    return find


def e3_findings(e3, results, extra):
    """E3 in 200 x 200 x 240 mm by N, and in 300 x 300 x 320 mm."""
    find = []
    if e3[(6, 200, 240)]:
        b3 = box_baseline(e3[(6, 200, 240)], results, extra)
        t = "- **E3 (Re 11.6), 200 x 200 x 240 mm:** %.4f m/s (%s) at N = 6" % (e3[(6, 200, 240)]["terminal_speed"], terminal_error(e3[(6, 200, 240)]))
        if b3:
            t += " (experiment's box: peak %+.1f %%, wall effect %.3f)" % (b3["peak_error_pct"], b3["peak_speed"] / e3[(6, 200, 240)]["terminal_speed"])
        if e3[(9, 200, 240)]:
            b9 = box_baseline(e3[(9, 200, 240)], results, extra)
            t += "; %.4f m/s (%s) at N = 9" % (e3[(9, 200, 240)]["terminal_speed"], terminal_error(e3[(9, 200, 240)]))
            if b9:
                t += " (experiment's box: %+.1f %%, wall effect %.3f)" % (b9["peak_error_pct"], b9["peak_speed"] / e3[(9, 200, 240)]["terminal_speed"])
        if e3[(12, 200, 240)]:
            t += "; %.4f m/s (%s) at N = 12" % (e3[(12, 200, 240)]["terminal_speed"], terminal_error(e3[(12, 200, 240)]))
        if e3[(6, 300, 320)]:
            t += "; %.4f m/s (%s) at N = 6 in 300 x 300 x 320 mm" % (e3[(6, 300, 320)]["terminal_speed"], terminal_error(e3[(6, 300, 320)]))
            if e3[(9, 200, 240)]:
                dd = e3[(6, 300, 320)]["terminal_error_pct"] - e3[(6, 200, 240)]["terminal_error_pct"]
                t += (". Applying the N = 6 change from 200 x 200 x 240 to 300 x 300 x 320 mm (%+.1f %%) to N = 9 would "
                      "put N = 9 near %+.1f %% (an estimate, not a run)" % (dd, e3[(9, 200, 240)]["terminal_error_pct"] + dd))
        find.append(t + ". The experiment's box takes about 3 % off E3's speed, so E3's small in-box errors at N = 6-7.5 "
                    "(main table) were a too-fast sphere meeting the walls, as suspected under Findings.")
    return find


def e2_findings(e2):
    """E2 in 200 x 200 x 240 mm against u_inf and the drag laws."""
    find = []
    e2_runs = [(n, e2[(n, 200, 240)]) for n in (6, 9, 12) if e2[(n, 200, 240)]]
    if e2_runs:
        sn, cgw = drag_law_velocity("E2", "sn"), drag_law_velocity("E2", "cgw")
        find.append(
            "- **E2 (Re 4.1), 200 x 200 x 240 mm, Mach 0.1:** " + "; ".join(
                "%.4f m/s at N = %g (tau %.2f; %s of u_inf, %+.1f / %+.1f %% of Schiller-Naumann / Clift-Grace-Weber)" % (
                    r["terminal_speed"], n, r["tau"], terminal_error(r), 100 * (r["terminal_speed"] / sn - 1), 100 * (r["terminal_speed"] / cgw - 1))
                for n, r in e2_runs) + ". Like E1, E2 settles faster than its u_inf and converges towards the drag laws "
            "with N; its small in-box errors (main table) were the experiment's walls.")
    return find


def e4_n16_findings(e4, wide):
    """E4 at N = 16 against N = 12 in the 150 mm box, and on a GPU in 210 mm."""
    find = []
    a12, a16 = e4[(12, 150, 240)], e4[(16, 150, 240)]
    if a12 and a16:
        t = ("- **E4 at N = 16** (150 x 150 x 240 mm: a 200 mm wide box at N = 16 is 213.3 cells wide, and 210 mm "
             "needs 12.8 M cells, above the 8.4 M that lavapipe's 128 MiB storage binding allows): %.4f m/s (%s) "
             "against %.4f m/s (%s) at N = 12 in the same box, %+.2f %% from N = 12 to 16" % (
                 a16["terminal_speed"], terminal_error(a16), a12["terminal_speed"], terminal_error(a12),
                 100 * (a16["terminal_speed"] / a12["terminal_speed"] - 1)))
        if e4[(12, 200, 240)]:
            wall = e4[(12, 200, 240)]["terminal_error_pct"] - a12["terminal_error_pct"]
            t += ("; the 150 mm box costs %.1f %% of u_inf against 200 mm at N = 12, so N = 16 in 200 x 200 x 240 mm "
                  "would be near %+.1f %% (an estimate)" % (wall, a16["terminal_error_pct"] + wall))
        g16 = find_run(wide, "E4", 16, 210, 240)
        if g16:
            t += ("; measured on a GPU in 210 x 210 x 240 mm: %.4f m/s (%s)" % (g16["terminal_speed"], terminal_error(g16)))
        find.append(t + ".")
    return find


def widest_runs(wide):
    """(case, N, run) of the widest box run per case and N."""
    verdict = []
    for case in CASES:
        for n in sorted({r["N"] for r in wide if r["case"] == case}):
            w = widest(wide, case, n)
            if w:
                verdict.append((case, n, w))
    return verdict


def verdict_headline(verdict):
    """The verdict against the target (3 % of u_inf) from the widest box run per case and N."""
    inside = ["%s N = %g (%s)" % (c, n, terminal_error(w)) for c, n, w in verdict if abs(w["terminal_error_pct"]) < 2.95]
    edge = ["%s N = %g (%s)" % (c, n, terminal_error(w)) for c, n, w in verdict if 2.95 <= abs(w["terminal_error_pct"]) <= 3.5]
    outside = ["%s N = %g (%s)" % (c, n, terminal_error(w)) for c, n, w in verdict if abs(w["terminal_error_pct"]) > 3.5]
    return (
        "**Against u_inf in the widest box run per case and N: within 3 %%:** %s; **at the limit (3.0-3.5 %%):** %s; "
        "**outside:** %s. %s" % (", ".join(inside) or "none", ", ".join(edge) or "none", ", ".join(outside) or "none",
                                 HEADLINE_END))


def operator_errors(wide, opw):
    """The larger-box runs of other operators against TRT's in the same box."""
    ops_w = []
    for r in sorted(opw, key=lambda r: (r["case"], r["N"], r["op"])):
        t = find_run(wide, r["case"], r["N"], r["box"][0] * 1e3, r["box"][2] * 1e3)
        if "terminal_speed" in r and t:
            ops_w.append("%s N = %g %s %s (TRT %s)" % (r["case"], r["N"], op_name(r["op"]), terminal_error(r), terminal_error(t)))
    return ops_w


def law_check(verdict):
    """The widest-box terminal speeds against the drag laws' terminal velocities: (headline sentence, finding)."""
    if not verdict:
        return None
    rows = []
    for case, n, w in verdict:
        sn, cgw = drag_law_velocity(case, "sn"), drag_law_velocity(case, "cgw")
        rows.append("%s N = %g %+.1f %% / %+.1f %%" % (case, n, 100 * (w["terminal_speed"] / sn - 1), 100 * (w["terminal_speed"] / cgw - 1)))
    e1 = [(n, w) for c, n, w in verdict if c == "E1"]
    head = ""
    if e1:
        n, w = max(e1, key=lambda t: t[0])
        sn = drag_law_velocity("E1", "sn")
        head = ("**E1's excess is mostly its reference:** u_inf = %.3f m/s for E1 is %.1f %% below the Schiller-Naumann "
                "terminal velocity (%.4f m/s); against that law E1 at N = %g in %s settles %+.1f %% off, and a sphere "
                "held in a stream at Re 1 (validation/lbm/REPORT.md, 8 cells per diameter, confinement fitted out) "
                "has a drag 2.2 %% below the law." % (
                    CASES["E1"]["u_inf"], 100 * (1 - CASES["E1"]["u_inf"] / sn), sn, n,
                    "%g x %g x %g mm" % tuple(round(L * 1e3, 3) for L in w["box"]), 100 * (w["terminal_speed"] / sn - 1)))
    find = ("- **The widest-box terminal speeds against the drag laws' terminal velocities** (Schiller-Naumann / "
            "Clift-Grace-Weber; the laws scatter by several percent around their data, so this is a cross-check, "
            "not the target's reference): " + "; ".join(rows) + ".")
    abraham = ", ".join("%s %+.1f %%" % (case, 100 * (drag_law_velocity(case, "abraham") / CASES[case]["u_inf"] - 1))
                        for case in CASES)
    find += ("\n- **Where u_inf comes from:** the terminal velocity of Abraham's (1970) drag correlation, "
             "Cd = 24/9.06^2 (1 + 9.06/sqrt(Re))^2, computed here for each case's fluid and sphere, lies within 0.8 %% "
             "of the reference u_inf of all four cases (%s): u_inf is a correlation's value, not a measurement in "
             "an unbounded fluid, and at Re 1.5-4 that correlation gives 7-9 %% more drag than Schiller-Naumann "
             "and Clift-Grace-Weber (terminal velocities %.1f / %.1f %% (E1) and %.1f / %.1f %% (E2) above u_inf). "
             "So at low Re the target (3 %% of u_inf) asks the simulated sphere to match one drag law among "
             "several that differ by more than 3 %%." % (
                 abraham,
                 100 * (drag_law_velocity("E1", "sn") / CASES["E1"]["u_inf"] - 1),
                 100 * (drag_law_velocity("E1", "cgw") / CASES["E1"]["u_inf"] - 1),
                 100 * (drag_law_velocity("E2", "sn") / CASES["E2"]["u_inf"] - 1),
                 100 * (drag_law_velocity("E2", "cgw") / CASES["E2"]["u_inf"] - 1)))
    return head, find


HEADLINE_END = (
    "So, once the experiment's walls are taken away (TRT, as in the main table): E3 (the seed paper's case) "
    "comes within 3 % of u_inf at N = 9 and 12 (+1.0 %, +0.6 % in 200 x 200 x 240 mm); E4 converges to about "
    "-3 % (-3.3 % at N = 12 and -3.2 % at N = 16 in 150 x 150 x 240 mm, -3.0 % at N = 12 in 200 x 200 x 240 mm; "
    "wider boxes take a few tenths of a percent off), at the edge of the target; E1 and E2 settle 7-9 % faster "
    "than their u_inf at N = 9 and come closer with N, but u_inf is the terminal velocity of Abraham's "
    "correlation, which at Re 1.5-4 gives 7-9 % more drag than Schiller-Naumann and Clift-Grace-Weber: against "
    "Clift-Grace-Weber every case is within 1.6 % at N = 9 (E1 -0.2 %, E2 +1.2 %, E3 +0.1 %, E4 -1.6 %). BGK "
    "(measured in 200 x 200 x 240 mm) makes every case 1-2.5 % of u_inf slower than TRT: E3 then comes within "
    "1 % at N = 6 and 9, E4 moves further off (-4.6 % at N = 6) and E1 stays far too fast (+11.8 %). The target "
    "of issue 5 (within 3 % of u_inf at N <= 16) is therefore met for E3, at its edge for E4 (converged in N near "
    "-3 %), and not met for E1 and E2 against their u_inf, which Schiller-Naumann and Clift-Grace-Weber do not "
    "reproduce either (5-9 % apart). The small in-box errors of E1 and E2 at N = 9-12 in the table below owe much to the "
    "experiment's walls, which slow the simulated low-Re sphere by 5-11 %.")
MEANING_END = (
    "Consequences:\n\n"
    "- the box slows the simulated sphere a lot at low Re (E1) and by a few percent at higher Re (E3, E4; for "
    "E4 about a third of it because 120 mm of fall is too short for it to reach its plateau);\n"
    "- a small error in the experiment's box can hide a large error against u_inf: E1's +1.5 % in the box "
    "at N = 6 is +14 % in a 300 mm wide box. The main table's errors are not the method's error against "
    "u_inf; the larger-box numbers are (section \"Larger boxes\");\n"
    "- in the larger boxes the simulated sphere is too fast at low Re (E1, and E3 at N = 6) and too slow "
    "at the highest Re (E4); the error changes sign with Re (and with tau, which falls with Re at fixed "
    "Mach), which points at the IMB boundary's effective size, not at the box; that size also depends on "
    "the collision operator (section \"Operators\": in a larger box BGK makes the sphere 1-2.5 % of u_inf "
    "slower than TRT in every case run, closer to u_inf for E3, further for E4; no operator fixes E1);\n"
    "- the experiment itself, for E1 (its measured speed and gap over time, digitized from the paper's "
    "figures): EXPERIMENT.md (`experiment.py`, runs with the current code in the experiment's box at "
    "tau 0.85-1.2). At tau 1.03 the plateau speed (1.7-2.5 s) is +4.7 / -2.1 / -4.4 / -5.6 % of the "
    "measured speed at N = 6 / 9 / 12 / 15 and +10.2 / +3.0 / +0.6 / -0.7 % of the measured gap's "
    "slope, converging (steps of 2.3 then 1.2 % from 9 to 15 cells); the two measured curves disagree "
    "with each other by 5 % (integrated from rest, the measured speed puts the sphere on the floor by "
    "about 3.4 s, when the measured gap still reads 0.6 d), and from N = 12 the simulated plateau lies "
    "at the gap's slope; the speed over the first 3 s is within 1.05-1.71 mm/s rms of the measured one "
    "at N = 9-15. The other cases' measured curves are not in the reference files.")
WIDE_END = ""

"""What the fluidized bed is measured against, for validation/imb/fluidized_bed.py.

A grain settling alone (Schiller-Naumann), the bed's voidage by Richardson & Zaki (1954) with and
without their wall term, and the drag in Tenneti, Garg & Subramaniam's (2011) fixed random arrays
(the voidage at which they carry a grain's buoyant weight).
"""
import math

import ten_cate_analysis  # validation/imb/ten_cate.py's parts: a drag law's terminal velocity
from fluidized_bed_scenes import D, G, MU, NU, RHO_F, RHO_P, inflow, width_y


def settling_reynolds():
    """(Archimedes number, Re_t of one grain settling alone by Schiller-Naumann's drag)."""
    ar = G * D**3 * (RHO_P / RHO_F - 1.0) / NU**2
    u_t = ten_cate_analysis.terminal_velocity(RHO_F, MU, RHO_P, D, "sn", 0.1)
    return ar, u_t * D / NU


def richardson_zaki(re_, depth):
    """(n, voidage unbounded, voidage with the wall term) of Richardson & Zaki (1954) at Re:
    U / u_i = eps^n with n = (4.7 + 0.41 Re_t^0.75) / (1 + 0.175 Re_t^0.75) (Rowe 1987) and
    log10 u_i = log10 u_t - d / D, D the narrow width of the slab."""
    _, re_t = settling_reynolds()
    n = (4.7 + 0.41 * re_t**0.75) / (1.0 + 0.175 * re_t**0.75)
    ratio = re_ / re_t
    walled = ratio / 10.0 ** (-D / width_y(depth))
    return n, ratio ** (1.0 / n), (walled ** (1.0 / n) if walled < 1.0 else float("nan"))


def tenneti(phi, re_):
    """Tenneti, Garg & Subramaniam (2011): the mean force on a sphere of a fixed random array, the
    mean pressure gradient's share included, over 3 pi mu d U (U superficial, Re = U d / nu); the
    same law as lbm-server's validate/bed_drag.rs."""
    eps = 1.0 - phi
    return ((1.0 + 0.15 * re_**0.687) / eps**3 + 5.81 * phi / eps**3 + 0.48 * phi ** (1.0 / 3.0) / eps**4
            + phi**3 * re_ * (0.95 + 0.61 * phi**3 / eps**2))


def buoyant_weight(re_):
    """A grain's buoyant weight over 3 pi mu d U at Re (U = Re nu / d)."""
    return (RHO_P - RHO_F) * G * math.pi / 6.0 * D**3 / (3.0 * math.pi * MU * D * inflow(re_))


def tenneti_voidage(re_):
    """The voidage at which Tenneti et al.'s random arrays carry a grain's buoyant weight at Re
    (bisection)."""
    low, high = 0.4, 0.99
    for _ in range(60):
        mid = 0.5 * (low + high)
        if tenneti(1.0 - mid, re_) > buoyant_weight(re_):
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)

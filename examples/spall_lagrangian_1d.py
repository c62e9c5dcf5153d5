#!/usr/bin/env python3
"""An independent reference for examples/spall.toml: the same flyer-plate impact in a 1D
Lagrangian finite-difference code (staggered grid, von Neumann-Richtmyer viscosity), to tell
the acoustic pull-back relation's own error from SPH's.

Same physics as the deck: Al 6061-T6 (Mie-Grueneisen rho0 = 2703 kg/m3, c0 = 5240 m/s,
S1 = 1.40, Gamma0 = 1.97; von Mises G = 27.6 GPa, Y0 = 0.29 GPa, in uniaxial strain), a 0.5 mm
flyer at 400 m/s on a 3 mm target, an interface that carries no tension. A cell fails for good
the moment its largest principal stress (sigma_xx in uniaxial strain) exceeds sigma_s; a failed
cell carries no tension. (strike's crack grows across a particle in 1.25 dp/c_L instead.)

Prints, per spall strength and cell size, the free face's peak and pull-back minimum (as
strike.validate.pull_back reads them) and the strength read back by 1/2 rho0 c dv with c the
longitudinal speed c_L and with the bulk speed c0. Needs numpy:

    python3 examples/spall_lagrangian_1d.py [--hydro] [--cells-um 20,10,2,1]

With --nylon: the library's nylon 6/6 instead (Mie-Grueneisen rho0 = 1140 kg/m3, c0 = 2570 m/s,
S1 = 1.849, Gamma0 = 0.87, hydrodynamic, spall strength 0.23 GPa), followed to 1.45 us, the
reference of tests/verification_materials.rs's nylon spall. Its pulse is square, not
triangular, so the pull-back minimum is read as the lowest free-face velocity after the face
first passes 350 m/s.

With --tuler-butcher s0,lambda,K_f: Tuler & Butcher's criterion instead of the spall strength
(a cell fails once the integral of (sigma_xx - s0)^lambda dt reaches K_f; s0 in GPa, K_f in
Pa^lambda s), the reference of tests/verification_materials.rs's Tuler-Butcher flyer plate;
--flyer-mm and --speed change the flyer.
"""
import argparse

import numpy as np

RHO0, C0, S1, GAMMA0 = 2703.0, 5240.0, 1.40, 1.97
G, Y0 = 27.6e9, 0.29e9
FLYER, TARGET, V0, END = 0.5e-3, 3.0e-3, 400.0, 1.2e-6
NYLON = dict(RHO0=1140.0, C0=2570.0, S1=1.849, GAMMA0=0.87, END=1.45e-6)


def pressure(rho, e):
    """Mie-Grueneisen with the Hugoniot as reference in compression, linear in tension."""
    mu = rho / RHO0 - 1.0
    cold = np.where(
        mu > 0.0,
        RHO0 * C0**2 * mu * (1.0 + (1.0 - 0.5 * GAMMA0) * mu) / (1.0 - (S1 - 1.0) * mu) ** 2,
        RHO0 * C0**2 * mu,
    )
    return cold + GAMMA0 * RHO0 * e


def free_face(sigma_s, dx, strength=True, cfl=0.3, tuler_butcher=None):
    """The target's free-face velocity history [(t, u)], and where its failed cells started
    (their centres' material coordinate x0 from the impact face). `tuler_butcher`:
    (sigma_0, lambda, K_f) instead of the threshold sigma_s: a cell fails once the integral of
    (sigma_xx - sigma_0)^lambda dt over the time sigma_xx > sigma_0 reaches K_f."""
    nf, nt = round(FLYER / dx), round(TARGET / dx)
    n = nf + nt
    x = np.arange(n + 1) * dx - FLYER
    u = np.where(np.arange(n + 1) < nf, V0, 0.0)
    u[nf] = 0.5 * V0
    m = RHO0 * dx * np.ones(n)
    node_mass = np.zeros(n + 1)
    node_mass[:-1] += 0.5 * m
    node_mass[1:] += 0.5 * m
    rho, e, s = RHO0 * np.ones(n), np.zeros(n), np.zeros(n)
    failed = np.zeros(n, bool)
    impulse = np.zeros(n)
    g = G if strength else 0.0
    t, trace = 0.0, []
    while t < END:
        width = np.diff(x)
        c = np.sqrt(C0**2 * rho / RHO0 + 4.0 / 3.0 * g / rho)
        dt = cfl * np.min(width / c)
        du = np.diff(u)
        q = np.where(du < 0.0, rho * (2.0 * du**2 + 0.1 * c * np.abs(du)), 0.0)
        sxx = -pressure(rho, e) + s
        # The flyer's last cell stands for the contact: it never pulls on the target.
        sxx = np.where(failed | (np.arange(n) == nf - 1), np.minimum(sxx, 0.0), sxx)
        total = sxx - q
        force = np.concatenate((total, [0.0])) - np.concatenate(([0.0], total))
        u = u + force / node_mass * dt
        x = x + u * dt
        rate = np.diff(u) / np.diff(x)
        rho = m / np.diff(x)
        e = e + total * rate * dt / rho
        if strength:
            s = np.clip(s + 4.0 / 3.0 * G * rate * dt, -2.0 / 3.0 * Y0, 2.0 / 3.0 * Y0)
        if tuler_butcher is None:
            failed |= (-pressure(rho, e) + s) > sigma_s
        else:
            s0, lam, k_f = tuler_butcher
            impulse += np.maximum(-pressure(rho, e) + s - s0, 0.0) ** lam * dt
            failed |= impulse >= k_f
        t += dt
        trace.append((t, u[-1]))
    x0 = (np.arange(n) + 0.5) * dx - FLYER
    return trace, x0[failed & (x0 > 0.0)]


def pull_back(trace):
    """(u_max, u_min) as strike's validate::pull_back reads a free-face trace."""
    u_max, k = 0.0, 0
    while k < len(trace):
        u = trace[k][1]
        if u_max > 10.0 and u < 0.95 * u_max:
            break
        u_max = max(u_max, u)
        k += 1
    u_min = u_max
    for _, u in trace[k:]:
        u_min = min(u_min, u)
        if u > u_min + 0.1 * (u_max - u_min):
            break
    return u_max, u_min


def lowest_after_rise(trace, rise=350.0):
    """The lowest free-face velocity after the face first passes `rise` (a square pulse)."""
    first = next((k for k, (_, u) in enumerate(trace) if u > rise), None)
    return float("nan") if first is None else min(u for _, u in trace[first:])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hydro", action="store_true", help="no strength (a fluid that spalls)")
    ap.add_argument("--cells-um", default="20,10,2,1", help="cell sizes in micrometres")
    ap.add_argument(
        "--strengths-gpa", default=None, help="spall strengths (0.6,1.0,1.5; --nylon: 0.23)"
    )
    ap.add_argument("--nylon", action="store_true", help="the library's nylon 6/6 (see above)")
    ap.add_argument(
        "--tuler-butcher",
        default=None,
        help="sigma_0 (GPa), lambda, K_f (Pa^lambda s) instead of a spall strength, e.g. 0.7,2,1e9",
    )
    ap.add_argument("--speed", type=float, default=None, help="the flyer's speed (m/s; 400)")
    ap.add_argument("--flyer-mm", type=float, default=None, help="the flyer's thickness (0.5)")
    a = ap.parse_args()
    if a.speed is not None:
        globals()["V0"] = a.speed
    if a.flyer_mm is not None:
        globals()["FLYER"] = a.flyer_mm * 1e-3
    if a.nylon:
        globals().update(NYLON)
        a.hydro = True
    if a.strengths_gpa is None:
        a.strengths_gpa = "0.23" if a.nylon else "0.6,1.0,1.5"
    c_l = np.sqrt(C0**2 + (0.0 if a.hydro else 4.0 / 3.0 * G / RHO0))
    tb = None
    if a.tuler_butcher is not None:
        s0, lam, k_f = (float(v) for v in a.tuler_butcher.split(","))
        tb = (s0 * 1e9, lam, k_f)
        a.strengths_gpa = a.tuler_butcher.split(",")[0]
    for sigma in (float(v) * 1e9 for v in a.strengths_gpa.split(",")):
        for dx in (float(v) * 1e-6 for v in a.cells_um.split(",")):
            trace, failed_x0 = free_face(sigma, dx, strength=not a.hydro, tuler_butcher=tb)
            u_max, u_min = pull_back(trace)
            if a.nylon:
                u_max, u_min = V0, lowest_after_rise(trace)
            plane = failed_x0.mean() if failed_x0.size else float("nan")
            read_l = 0.5 * RHO0 * c_l * (u_max - u_min)
            read_0 = 0.5 * RHO0 * C0 * (u_max - u_min)
            print(
                f"sigma_s {sigma / 1e9:.2f} GPa, dx {dx * 1e6:g} um: u_max {u_max:.1f}, "
                f"u_min {u_min:.1f} m/s; by c_L {read_l / 1e9:.3f} GPa "
                f"({100 * (read_l / sigma - 1):+.1f} %), by c0 {read_0 / 1e9:.3f} GPa "
                f"({100 * (read_0 / sigma - 1):+.1f} %); spall plane (mean x0 of the failed cells) "
                f"{plane * 1e3:.4f} mm"
            )


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""An independent reference for examples/taylor_bar.toml: the same 42CrMo4 Taylor bar in a 2D
axisymmetric explicit Lagrangian finite-element code, to tell whether the finite-element
results VALIDATION.md quotes (DynELA and Abaqus, one mesh of about 0.4 mm) are converged, and
what the rod does on strike's own wall; with --material, the same for the copper rods of
examples/taylor_ofhc.toml and examples/taylor_copper.toml.

Same physics as the deck: L0 = 32.4 mm, R0 = 3.2 mm, 287 m/s, 80 us; Johnson-Cook A = 806 MPa,
B = 614 MPa, n = 0.168, C = 0.0089, m = 1.1, reference rate 1 /s (the rate term never below
1), T_room 293.15 K, T_melt 1813.15 K, heating chi w_p / c_p with c_p = 460 J/(kg K) and
chi = 0.9 (w_p the plastic work per unit mass, as strike's material::johnson_cook); rho0 = 7830
kg/m3, E = 206.9 GPa, nu = 0.3; the library's Mie-Grueneisen EOS (c0 = 4578 m/s, S1 = 1.33,
Gamma0 = 1.67).

The method: 4-node quadrilaterals in (r, z), one-point quadrature (the hoop strain rate from
the element's mean radial velocity over its centroid radius, the hoop stress's nodal force
sigma_tt A / 4 per radian), Flanagan & Belytschko's (1981) viscous hourglass control
(coefficient 0.1), lumped masses, central differences at 0.3 of the element transit time;
Jaumann rate; radial return onto the Johnson-Cook surface by Newton's method on the step's
plastic strain; a bulk viscosity with Abaqus/Explicit's default coefficients (linear 0.06,
quadratic 1.2), in compression only. The wall z = 0 is frictionless: `--wall free` (default)
is strike's `[[wall]]`, which the bottom nodes may leave; `--wall bonded` holds them on the
plane, as DynELA's benchmark script (Samples/Taylor/Taylor-3D/Taylor.py of
pantale/DynELA-v.-4.0) does.

Prints the final length (the axis from the bottom node to the top one), the impact-face
diameter (twice the largest radius of the bottom row of nodes, the bottom face's edge, where
DynELA reads it) and the peak plastic strain; `--history` also every 5 us. Needs numpy:

    python3 examples/taylor_fe_axisymmetric.py [--elements-across 8,16,32] [--wall bonded]
        [--chi 0] [--history] [--material ofhc|kamoulakos] [--v0 146]

Measured (2026-12-05; 8 / 16 / 32 elements across R0, i.e. 0.4 / 0.2 / 0.1 mm; 15 s / 75 s /
9 min on one core):
    bonded:          length 26.544 / 26.532 / 26.526 mm, face 11.262 / 11.286 / 11.286 mm,
                     peak eps_p 1.773 / 1.824 / 1.852
    free (strike's): length 26.475 / 26.459 / 26.450 mm, face 11.343 / 11.377 / 11.390 mm,
                     peak eps_p 1.893 / 1.958 / 2.018; the bottom lifts 0.70-0.73 mm by 80 us
    free, chi = 0:   length 26.550 / 26.536 mm, face 10.385 / 10.408 mm, peak eps_p 1.440 / 1.491
Plane strain (`--plane-strain`: a slab 6.4 mm thick, x for r, no hoop terms; the face is then
the slab's width at the wall), free wall, chi = 0 (2026-12-05): at 287 m/s face 16.461 / 16.505
mm at 8 / 16 elements; at 150 m/s (`--v0 150`) 9.039 / 9.036 mm, length 30.733 / 30.724 mm,
peak eps_p 0.738 / 0.767. A cheap 2D test bed for strike's Taylor face (docs/open-problems.md).
Johnson & Cook's OFHC copper rods (`--material ofhc`, examples/taylor_ofhc.toml, free wall;
2026-12-06; 8 / 16 / 32 elements across R0 = 3.81 mm): at 190 m/s length 17.320 / 17.340 /
17.355 mm, face 14.532 / 14.670 / 14.744 mm, peak eps_p 2.18 / 2.44 / 2.70 (35 s / 2 min /
15 min); at 146 m/s 19.794 / 19.804 / 19.813 and 12.012 / 12.086 / 12.133 mm; at 130 m/s
20.655 / 20.662 / 20.669 and 11.235 / 11.294 / 11.325 mm. The recovered rods (16.205, 18.694,
19.558 mm long; faces 13.564, 10.668, 9.906 mm) are shorter and narrower: the model's own
error, which strike's `taylor_ofhc` case therefore does not hold its faces to.
Kamoulakos's copper benchmark (`--material kamoulakos`, examples/taylor_copper.toml; 8 / 16
elements across R0, 2026-12-06): bonded, length 21.450 / 21.429 mm, face 14.347 / 14.423 mm,
peak eps_p 2.82 / 3.13, the published 21.42-21.47 mm, 14.0-14.4 mm and 2.7-3.2; free, as
strike's wall, 21.482 / 21.462 mm, 14.595 / 14.687 mm, peak eps_p 3.17 / 3.71.
The bonded mesh of 0.4 mm gives the published 26.52-26.56 mm, 11.15-11.22 mm (+0.4 %) and
1.78-1.84, and refining it moves the face by +0.2 % and then not at all: the published face is
the converged one of this continuum, which heats without localising at these meshes.
"""
import argparse
import time

import numpy as np

L0, R0, V0, T_END = 32.4e-3, 3.2e-3, 287.0, 80e-6
RHO0, E, NU = 7830.0, 206.9e9, 0.3
G = E / (2 * (1 + NU))
C0, S1, GAMMA0 = 4578.0, 1.33, 1.67
A, B, N, C, M = 806e6, 614e6, 0.168, 0.0089, 1.1
T0, TM, CP = 293.15, 1813.15, 460.0
LINEAR = None  # --material kamoulakos: (K, Y0, H), a linear EOS and linear hardening
PLANE = False  # --plane-strain: a slab 2 R0 wide, unit depth, x for r and no hoop terms
HOURGLASS = np.array([1.0, -1.0, 1.0, -1.0])


def pressure(rho, e):
    """Mie-Grueneisen with the Hugoniot as reference in compression, linear in tension."""
    if LINEAR is not None:
        return LINEAR[0] * (rho / RHO0 - 1)
    eta = 1 - RHO0 / rho
    ph = np.where(eta > 0, RHO0 * C0**2 * eta / (1 - S1 * eta) ** 2, RHO0 * C0**2 * eta)
    return ph * (1 - 0.5 * GAMMA0 * eta) + GAMMA0 * RHO0 * e


def flow_stress(eps_p, rate, w_p, chi):
    """Johnson-Cook Y(eps_p, rate, T), T = T0 + chi w_p / c_p."""
    if LINEAR is not None:
        return LINEAR[1] + LINEAR[2] * eps_p
    t_star = np.clip(chi * w_p / CP / (TM - T0), 0.0, 1.0)
    return (
        (A + B * np.maximum(eps_p, 1e-12) ** N)
        * (1 + C * np.log(np.maximum(rate, 1.0)))
        * (1 - t_star**M)
    )


def geometry(x, conn):
    """Nodal coordinates of each element, its area, the shape functions' r and z derivatives
    at its centre, and its centroid radius."""
    r = x[conn, 0]
    z = x[conn, 1]
    area = 0.5 * ((r[:, 2] - r[:, 0]) * (z[:, 3] - z[:, 1]) - (r[:, 3] - r[:, 1]) * (z[:, 2] - z[:, 0]))
    two_a = 2 * area[:, None]
    br = np.stack([z[:, 1] - z[:, 3], z[:, 2] - z[:, 0], z[:, 3] - z[:, 1], z[:, 0] - z[:, 2]], axis=1) / two_a
    bz = np.stack([r[:, 3] - r[:, 1], r[:, 0] - r[:, 2], r[:, 1] - r[:, 3], r[:, 2] - r[:, 0]], axis=1) / two_a
    return r, z, area, br, bz, (np.ones_like(area) if PLANE else r.mean(axis=1))


def run(n_r, wall, chi, hourglass, history):
    n_z = int(round(n_r * L0 / R0))
    rr, zz = np.meshgrid(np.linspace(0, R0, n_r + 1), np.linspace(0, L0, n_z + 1), indexing="ij")
    x = np.stack([rr.ravel(), zz.ravel()], axis=1)
    nodes = x.shape[0]
    idx = np.arange(nodes).reshape(n_r + 1, n_z + 1)
    # Counterclockwise in (r, z).
    conn = np.stack(
        [idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()], axis=1
    )
    n_el = conn.shape[0]
    on_axis = x[:, 0] == 0.0
    bottom_row = idx[:, 0]
    _, _, area0, _, _, rbar0 = geometry(x, conn)
    mass = RHO0 * area0 * rbar0  # per radian
    nodal_mass = np.bincount(conn.ravel(), weights=np.repeat(mass / 4, 4), minlength=nodes)
    s = np.zeros((n_el, 4))  # deviator: rr, zz, tt, rz
    p = np.zeros(n_el)
    e = np.zeros(n_el)
    eps_p = np.zeros(n_el)
    w_p = np.zeros(n_el)
    vh = np.zeros_like(x)  # velocity at the half step
    vh[:, 1] = -V0
    force = np.zeros_like(x)
    t, steps, next_out = 0.0, 0, 5e-6
    r, z, area, br, bz, rbar = geometry(x, conn)
    while t < T_END:
        if (area <= 0).any():
            raise SystemExit(f"an element inverted at t = {t:.3e} s")
        diagonal = np.maximum(np.hypot(r[:, 2] - r[:, 0], z[:, 2] - z[:, 0]), np.hypot(r[:, 3] - r[:, 1], z[:, 3] - z[:, 1]))
        rho = mass / (area * rbar)
        c = np.sqrt(C0**2 + 4 * G / (3 * rho))
        dt = min(0.6 * (area / diagonal / c).min(), T_END - t + 1e-15)
        vr, vz = vh[conn, 0], vh[conn, 1]
        d_rr = (br * vr).sum(1)
        d_zz = (bz * vz).sum(1)
        dvr_dz = (bz * vr).sum(1)
        dvz_dr = (br * vz).sum(1)
        d_tt = 0.0 * rbar if PLANE else vr.mean(1) / rbar
        d_rz = 0.5 * (dvr_dz + dvz_dr)
        spin = 0.5 * (dvr_dz - dvz_dr)
        div = d_rr + d_zz + d_tt
        x = x + dt * vh
        r, z, area, br, bz, rbar = geometry(x, conn)
        rho = mass / (area * rbar)
        # Jaumann rate: the deviator turns with the spin in the r-z plane.
        mean = div / 3
        trial = np.empty_like(s)
        trial[:, 0] = s[:, 0] + dt * (2 * G * (d_rr - mean) + 2 * spin * s[:, 3])
        trial[:, 1] = s[:, 1] + dt * (2 * G * (d_zz - mean) - 2 * spin * s[:, 3])
        trial[:, 2] = s[:, 2] + dt * 2 * G * (d_tt - mean)
        trial[:, 3] = s[:, 3] + dt * (2 * G * d_rz + spin * (s[:, 1] - s[:, 0]))
        von_mises = np.sqrt(1.5 * (trial[:, :3] ** 2).sum(1) + 3 * trial[:, 3] ** 2)
        rate = np.sqrt(2 / 3 * ((d_rr - mean) ** 2 + (d_zz - mean) ** 2 + (d_tt - mean) ** 2 + 2 * d_rz**2))
        plastic = von_mises > flow_stress(eps_p, rate, w_p, chi)
        d_eps = np.zeros(n_el)
        if plastic.any():
            # Newton on sigma* - 3 G d = Y(eps_p + d, rate, w_p + heat of the step).
            def residual(d):
                heat = d * np.maximum(von_mises - 3 * G * d, 0) / rho
                return von_mises - 3 * G * d - flow_stress(eps_p + d, rate, w_p + heat, chi)

            for _ in range(30):
                f = residual(d_eps)
                slope = (residual(d_eps + 1e-8) - f) / 1e-8
                d_eps = np.where(plastic, np.maximum(d_eps - f / slope, 0.0), 0.0)
            trial *= np.where(plastic, (von_mises - 3 * G * d_eps) / np.maximum(von_mises, 1e-30), 1.0)[:, None]
        s = trial
        eps_p += d_eps
        w_p += d_eps * np.sqrt(1.5 * (s[:, :3] ** 2).sum(1) + 3 * s[:, 3] ** 2) / rho
        size = np.sqrt(area)
        q = np.where(div < 0, rho * size * (0.06 * c * -div + 1.2 * size * div**2), 0.0)
        work = s[:, 0] * d_rr + s[:, 1] * d_zz + s[:, 2] * d_tt + 2 * s[:, 3] * d_rz
        e += dt * (work - (p + q) * div) / rho
        p = pressure(rho, e)
        # Nodal forces per radian: -int B^T sigma r dA, and the hoop stress's -sigma_tt N_a A.
        sig_rr, sig_zz, sig_tt = s[:, 0] - p - q, s[:, 1] - p - q, s[:, 2] - p - q
        volume = (area * rbar)[:, None]
        f_r = -(sig_rr[:, None] * br + s[:, 3:4] * bz) * volume - (0.0 if PLANE else 0.25) * (sig_tt * area)[:, None]
        f_z = -(s[:, 3:4] * br + sig_zz[:, None] * bz) * volume
        # Flanagan-Belytschko viscous hourglass control.
        gamma = HOURGLASS - (HOURGLASS * x[conn, 0]).sum(1)[:, None] * br - (HOURGLASS * x[conn, 1]).sum(1)[:, None] * bz
        k = 0.25 * hourglass * rho * c * size * rbar
        f_r -= (k * (gamma * vh[conn, 0]).sum(1))[:, None] * gamma
        f_z -= (k * (gamma * vh[conn, 1]).sum(1))[:, None] * gamma
        force[:, 0] = np.bincount(conn.ravel(), weights=f_r.ravel(), minlength=nodes)
        force[:, 1] = np.bincount(conn.ravel(), weights=f_z.ravel(), minlength=nodes)
        vh = vh + dt * force / nodal_mass[:, None]
        vh[on_axis, 0] = 0.0
        if wall == "bonded":
            vh[bottom_row, 1] = 0.0
            x[bottom_row, 1] = 0.0
            r, z, area, br, bz, rbar = geometry(x, conn)  # the next step's, with the row on the plane
        else:
            # A node the next step would carry through the wall lands on it.
            through = x[:, 1] + dt * vh[:, 1] < 0
            vh[through, 1] = -x[through, 1] / dt
        t += dt
        steps += 1
        if history and t >= next_out:
            next_out += 5e-6
            print(
                f"  t {t * 1e6:5.1f} us: face {2 * x[bottom_row, 0].max() * 1e3:.3f} mm, bottom "
                f"{x[bottom_row, 1].min() * 1e3:.3f} mm, length {(x[idx[0, -1], 1] - x[idx[0, 0], 1]) * 1e3:.3f} mm, "
                f"peak eps_p {eps_p.max():.3f}"
            )
    return dict(
        length=x[idx[0, -1], 1] - x[idx[0, 0], 1],
        face=2 * x[bottom_row, 0].max(),
        eps_p=eps_p.max(),
        lift=x[bottom_row, 1].min(),
        steps=steps,
    )


def use_ofhc_copper():
    """Johnson & Cook's (1983) OFHC copper rod (examples/taylor_ofhc.toml): L0 = 25.4 mm,
    R0 = 3.81 mm, 190 m/s; the library's `ofhc_copper` (rho0 8930 kg/m3, G 47.7 GPa,
    Mie-Grueneisen c0 3940 m/s, S1 1.489, Gamma0 2.02: Steinberg 1996; Johnson-Cook A 90 MPa,
    B 292 MPa, n 0.31, C 0.025, m 1.09, T_melt 1356 K: Johnson & Cook 1983; c_p 383)."""
    global L0, R0, V0, RHO0, G, C0, S1, GAMMA0, A, B, N, C, M, TM, CP
    L0, R0, V0 = 25.4e-3, 3.81e-3, 190.0
    RHO0, G = 8930.0, 47.7e9
    C0, S1, GAMMA0 = 3940.0, 1.489, 2.02
    A, B, N, C, M = 90e6, 292e6, 0.31, 0.025, 1.09
    TM, CP = 1356.0, 383.0


def use_kamoulakos_copper():
    """The copper Taylor bar of Kamoulakos's (1990) finite-element benchmark
    (examples/taylor_copper.toml): L0 = 32.4 mm, R0 = 3.2 mm, 227 m/s; rho0 8930 kg/m3,
    E 117 GPa, nu 0.35, Y = 0.4 GPa + 0.1 GPa eps_p, no rate or temperature dependence; strike's
    linear EOS p = K (rho/rho0 - 1) with K = E / (3 (1 - 2 nu))."""
    global L0, R0, V0, RHO0, G, C0, LINEAR
    L0, R0, V0 = 32.4e-3, 3.2e-3, 227.0
    e, nu = 117e9, 0.35
    RHO0, G = 8930.0, e / (2 * (1 + nu))
    k = e / (3 * (1 - 2 * nu))
    C0 = (k / RHO0) ** 0.5
    LINEAR = (k, 0.4e9, 0.1e9)


def main():
    global PLANE, V0
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--elements-across", default="8,16", help="elements across R0, comma-separated")
    parser.add_argument("--wall", choices=["free", "bonded"], default="free")
    parser.add_argument("--chi", type=float, default=0.9, help="Taylor-Quinney factor")
    parser.add_argument("--hourglass", type=float, default=0.1, help="hourglass viscosity coefficient")
    parser.add_argument("--history", action="store_true")
    parser.add_argument("--plane-strain", action="store_true", help="a slab in plane strain instead")
    parser.add_argument("--v0", type=float, help="impact speed (m/s; default the rod's: 287, ofhc 190, kamoulakos 227)")
    parser.add_argument("--material", choices=["42crmo4", "ofhc", "kamoulakos"], default="42crmo4")
    args = parser.parse_args()
    if args.material == "ofhc":
        use_ofhc_copper()
    elif args.material == "kamoulakos":
        use_kamoulakos_copper()
    PLANE = args.plane_strain
    V0 = args.v0 if args.v0 is not None else V0
    for n in (int(k) for k in args.elements_across.split(",")):
        start = time.time()
        got = run(n, args.wall, args.chi, args.hourglass, args.history)
        print(
            f"{n} elements across ({R0 / n * 1e3:.3f} mm), wall {args.wall}, chi {args.chi}: length "
            f"{got['length'] * 1e3:.3f} mm, face {got['face'] * 1e3:.3f} mm, peak eps_p {got['eps_p']:.3f}, "
            f"bottom lifted {got['lift'] * 1e3:.3f} mm ({got['steps']} steps, {time.time() - start:.0f} s)"
        )


if __name__ == "__main__":
    main()

"""Closed-form elasticity (and standard linear solid) solutions and the structured meshes used to
verify the solver against them.

Units mm, N, MPa; stresses tension-positive. Half-space problems use the project's axes: the
surface is y = 0, the body is y < 0, and the load pushes along -y (as an indentor does).

Meshes are returned as (points (N, dim), cells (M, dim + 1), regions {name: bool (N,)}).
"""
from __future__ import annotations

import numpy as np
from skfem import MeshTet, MeshTri


# --------------------------------------------------------------------------- closed forms
def lame_sphere(r, a, b, p, E, nu):
    """Thick sphere, inner radius a, outer b, internal pressure p.

    Returns u_r [mm], sigma_rr, sigma_tt (hoop) and mean stress [MPa] at radii r."""
    r = np.asarray(r, dtype=float)
    A = p * a**3 / (b**3 - a**3)
    return {"u_r": A / E * ((1 - 2 * nu) * r + (1 + nu) * b**3 / (2 * r**2)),
            "sigma_rr": A * (1 - b**3 / r**3), "sigma_tt": A * (1 + b**3 / (2 * r**3)),
            "mean": A * np.ones_like(r)}


def lame_cylinder(r, a, b, p, E, nu):
    """Thick cylinder in plane strain, inner radius a, outer b, internal pressure p.

    Returns u_r [mm], sigma_rr, sigma_tt, sigma_zz and mean stress [MPa] at radii r."""
    r = np.asarray(r, dtype=float)
    A = p * a**2 / (b**2 - a**2)
    return {"u_r": (1 + nu) * A / E * ((1 - 2 * nu) * r + b**2 / r),
            "sigma_rr": A * (1 - b**2 / r**2), "sigma_tt": A * (1 + b**2 / r**2),
            "sigma_zz": 2 * nu * A * np.ones_like(r), "mean": 2 * (1 + nu) / 3 * A * np.ones_like(r)}


def lame_sphere_layered(r, radii, E, nu, p):
    """Thick sphere of concentric layers radii[k] <= r <= radii[k+1] with moduli E[k], Poisson
    nu[k] (scalars broadcast), internal pressure p. In layer k: u_r = A_k r + B_k / r^2,
    sigma_rr = 3 K A - 4 G B / r^3, sigma_tt = 3 K A + 2 G B / r^3; u_r and sigma_rr continuous.

    Returns u_r, sigma_rr, sigma_tt, mean and the layer index (1-based) at radii r."""
    r = np.asarray(r, dtype=float)
    n = len(radii) - 1
    E, nu = np.broadcast_to(E, n).astype(float), np.broadcast_to(nu, n).astype(float)
    K, G = E / (3 * (1 - 2 * nu)), E / (2 * (1 + nu))
    M, rhs = np.zeros((2 * n, 2 * n)), np.zeros(2 * n)
    M[0, :2] = 3 * K[0], -4 * G[0] / radii[0] ** 3
    rhs[0] = -p
    for k in range(n - 1):
        c = radii[k + 1]
        M[1 + 2 * k, 2 * k:2 * k + 4] = c, 1 / c**2, -c, -1 / c**2
        M[2 + 2 * k, 2 * k:2 * k + 4] = 3 * K[k], -4 * G[k] / c**3, -3 * K[k + 1], 4 * G[k + 1] / c**3
    M[-1, -2:] = 3 * K[-1], -4 * G[-1] / radii[-1] ** 3
    AB = np.linalg.solve(M, rhs).reshape(n, 2)
    k = np.clip(np.searchsorted(radii, r, side="right") - 1, 0, n - 1)
    A, B = AB[k, 0], AB[k, 1]
    srr, stt = 3 * K[k] * A - 4 * G[k] * B / r**3, 3 * K[k] * A + 2 * G[k] * B / r**3
    return {"u_r": A * r + B / r**2, "sigma_rr": srr, "sigma_tt": stt, "mean": (srr + 2 * stt) / 3,
            "layer": k + 1}


def radial_traction(field):
    """Traction sigma . n of a radially symmetric field (sphere if x is 3D, cylinder if 2D) as a
    callable (x, n) -> (dim, ...) for `Model.load_vector(tractions=...)`; `field(r)` returns a
    dict with sigma_rr and sigma_tt (e.g. lambda r: lame_sphere(r, a, b, p, E, nu)).

    On a faceted mesh of the shell, loading both faceted surfaces with this traction makes the
    field the exact solution of the discrete geometry, so the error measured is the solver's alone
    (a uniform pressure on facets adds an O(h^2) geometry error and re-entrant-edge singularities)."""
    def traction(x, n):
        r = np.sqrt((x**2).sum(axis=0))
        ex = field(r)
        er = x / r
        return ex["sigma_tt"] * n + (ex["sigma_rr"] - ex["sigma_tt"]) * (er * n).sum(axis=0) * er
    return traction


def lame_traction(a, b, p, E, nu):
    """radial_traction of the Lame sphere (3D x) or plane-strain cylinder (2D x)."""
    sphere, cylinder = radial_traction(lambda r: lame_sphere(r, a, b, p, E, nu)), \
        radial_traction(lambda r: lame_cylinder(r, a, b, p, E, nu))
    return lambda x, n: (sphere if len(x) == 3 else cylinder)(x, n)


def flamant(x, y, P):
    """Line load P [N/mm] pushing along -y at the origin of the half-plane y < 0.

    sigma_r = -2 P cos(theta) / (pi r) with theta from the load direction; returns
    (sigma_xx, sigma_yy, sigma_xy) [MPa] at (x, y)."""
    x, d = np.asarray(x, dtype=float), -np.asarray(y, dtype=float)
    r4 = (x**2 + d**2) ** 2
    return -2 * P * x**2 * d / (np.pi * r4), -2 * P * d**3 / (np.pi * r4), 2 * P * x * d**2 / (np.pi * r4)


def boussinesq(x, y, z, P, E, nu):
    """Point load P [N] pushing along -y at the origin of the half-space y < 0.

    Returns displacement (n, 3) [mm] and stress (n, 3, 3) [MPa] (Johnson, Contact Mechanics, 3.2)."""
    x, z = np.asarray(x, dtype=float), np.asarray(z, dtype=float)
    d = -np.asarray(y, dtype=float)                       # depth
    s = np.hypot(x, z)                                    # distance from the load axis
    R = np.sqrt(s**2 + d**2)
    G = E / (2 * (1 + nu))
    ud = P / (4 * np.pi * G) * (d**2 / R**3 + 2 * (1 - nu) / R)          # along depth (-y)
    ur = P / (4 * np.pi * G) * (s * d / R**3 - (1 - 2 * nu) * s / (R * (R + d)))
    srr = P / (2 * np.pi) * ((1 - 2 * nu) / (R * (R + d)) - 3 * d * s**2 / R**5)
    stt = -P / (2 * np.pi) * (1 - 2 * nu) * (1 / (R * (R + d)) - d / R**3)
    sdd = -3 * P * d**3 / (2 * np.pi * R**5)
    srd = -3 * P * s * d**2 / (2 * np.pi * R**5)
    with np.errstate(invalid="ignore", divide="ignore"):
        c, sn = np.where(s > 0, x / s, 1.0), np.where(s > 0, z / s, 0.0)
    u = np.stack([ur * c, -ud, ur * sn], axis=-1)
    sig = np.zeros(x.shape + (3, 3))
    sig[..., 0, 0] = srr * c**2 + stt * sn**2
    sig[..., 2, 2] = srr * sn**2 + stt * c**2
    sig[..., 0, 2] = sig[..., 2, 0] = (srr - stt) * c * sn
    sig[..., 1, 1] = sdd
    sig[..., 0, 1] = sig[..., 1, 0] = -srd * c             # depth axis is -y
    sig[..., 2, 1] = sig[..., 1, 2] = -srd * sn
    return u, sig


def plane_strain_sed_incompressible(E, eps1):
    """Thesis appendix A: plane strain, nu = 0.5: SED = (2/3) E eps1^2 [MPa]."""
    return 2.0 / 3.0 * E * eps1**2


# --------------------------------------------------------------------------- structured meshes
def _prisms_to_tets(tri, nlayers, nverts):
    """Split prisms (triangle x radial layer) into 3 tets each, conforming (diagonals from the
    lower-index bottom vertex)."""
    tri = np.sort(tri, axis=1)
    cells = []
    for k in range(nlayers):
        a, b, c = (tri[:, i] + k * nverts for i in range(3))
        A, B, C = a + nverts, b + nverts, c + nverts
        cells += [np.column_stack(q) for q in ((a, b, c, C), (a, b, B, C), (a, A, B, C))]
    return np.vstack(cells)


def _triangle_grid(n):
    """Barycentric grid of the unit triangle with n divisions: points (m, 3) summing to 1, tris."""
    ij = [(i, j) for i in range(n + 1) for j in range(n + 1 - i)]
    index = {q: k for k, q in enumerate(ij)}
    lam = np.array([(i / n, j / n, 1 - (i + j) / n) for i, j in ij])
    tris = []
    for i, j in ij:
        if i + j < n:
            tris.append((index[i, j], index[i + 1, j], index[i, j + 1]))
        if i + j < n - 1:
            tris.append((index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]))
    return lam, np.array(tris)


def graded(r0, r1, n, ratio=1.0):
    """n + 1 values from r0 to r1 with successive spacings growing by `ratio`."""
    w = ratio ** np.arange(n)
    return r0 + (r1 - r0) * np.concatenate([[0], np.cumsum(w) / w.sum()])


def sphere_octant_shell(a, b, n_arc, n_rad, ratio=1.0):
    """Octant (x, y, z >= 0) of a spherical shell a <= r <= b as tetrahedra.

    Regions: inner, outer, sym_x (x = 0), sym_y, sym_z."""
    lam, tri = _triangle_grid(n_arc)
    direction = lam / np.linalg.norm(lam, axis=1, keepdims=True)
    radii = graded(a, b, n_rad, ratio)
    pts = np.vstack([r * direction for r in radii])
    cells = _prisms_to_tets(tri, n_rad, len(lam))
    rr = np.repeat(radii, len(lam))
    regions = {"inner": np.isclose(rr, a), "outer": np.isclose(rr, b),
               **{f"sym_{c}": np.isclose(pts[:, i], 0.0) for i, c in enumerate("xyz")}}
    return pts, cells, regions


def annulus_quarter(a, b, n_arc, n_rad, ratio=1.0):
    """Quarter annulus (x, y >= 0), a <= r <= b, as triangles. Regions: inner, outer, sym_x, sym_y."""
    r = graded(a, b, n_rad, ratio)
    t = np.linspace(0, np.pi / 2, n_arc + 1)
    R, T = np.meshgrid(r, t, indexing="ij")
    pts = np.column_stack([(R * np.cos(T)).ravel(), (R * np.sin(T)).ravel()])
    idx = np.arange(R.size).reshape(R.shape)
    q = np.column_stack([idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()])
    cells = np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    rr = R.ravel()
    regions = {"inner": np.isclose(rr, a), "outer": np.isclose(rr, b),
               "sym_x": np.isclose(pts[:, 0], 0.0), "sym_y": np.isclose(pts[:, 1], 0.0)}
    return pts, cells, regions


def box(xs, ys, zs=None):
    """Structured box on the grids xs, ys (, zs): triangles (2D) or tetrahedra (3D).

    Regions: xmin, xmax, ymin, ymax (, zmin, zmax)."""
    m = MeshTri.init_tensor(xs, ys) if zs is None else MeshTet.init_tensor(xs, ys, zs)
    pts = m.p.T
    regions = {}
    for i, c in enumerate("xyz"[:pts.shape[1]]):
        regions[f"{c}min"] = np.isclose(pts[:, i], pts[:, i].min())
        regions[f"{c}max"] = np.isclose(pts[:, i], pts[:, i].max())
    return pts, m.t.T, regions


def half_disc(r0, R, n_rad, n_arc, ratio=1.0):
    """Half disc y <= 0 of radius R about the origin, rings graded from r0 (a fan inside r0).

    Regions: surface (y = 0), far (r = R), patch (surface nodes with |x| <= r0)."""
    r = graded(r0, R, n_rad, ratio)
    th = np.linspace(-np.pi, 0, n_arc + 1)
    Rg, T = np.meshgrid(r, th, indexing="ij")
    pts = np.vstack([[0.0, 0.0], np.column_stack([(Rg * np.cos(T)).ravel(), (Rg * np.sin(T)).ravel()])])
    idx = 1 + np.arange(Rg.size).reshape(Rg.shape)
    q = np.column_stack([idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()])
    fan = np.column_stack([np.zeros(n_arc, dtype=int), idx[0, :-1], idx[0, 1:]])
    cells = np.vstack([fan, q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    x, y = pts[:, 0], pts[:, 1]
    surface = np.isclose(y, 0.0)
    return pts, cells, {"surface": surface, "far": np.isclose(np.hypot(x, y), R),
                        "patch": surface & (np.abs(x) <= r0 * (1 + 1e-9))}


# --------------------------------------------------------------------------- contact (Hertz; Johnson 1985)
def hertz_sphere(radius_mm, depth_mm, E_MPa, nu):
    """Rigid sphere on an elastic half-space: (force N, contact radius mm, peak pressure MPa)."""
    Es = E_MPa / (1 - nu * nu)
    a = np.sqrt(radius_mm * depth_mm)
    force = 4.0 / 3.0 * Es * np.sqrt(radius_mm) * depth_mm ** 1.5
    return force, a, 3 * force / (2 * np.pi * a * a)


def hertz_cylinder(radius_mm, force_N_per_mm, E_MPa, nu):
    """Rigid cylinder on an elastic half-plane (plane strain): (half-width mm, peak pressure MPa)."""
    Es = E_MPa / (1 - nu * nu)
    b = np.sqrt(4 * force_N_per_mm * radius_mm / (np.pi * Es))
    return b, 2 * force_N_per_mm / (np.pi * b)


def fine_then_growing(fine_mm, fine_len_mm, growth, total_mm, exact: bool = False):
    """Grid 0..>=total_mm: cells of fine_mm up to fine_len_mm, then each `growth` times the last.
    exact: the grid ends on total_mm instead (its last node moved there; a last cell thinner than
    half the one before is merged into it), for a body of a given size."""
    x = list(np.arange(0.0, fine_len_mm + 1e-9, fine_mm))
    h = fine_mm
    while x[-1] < total_mm:
        h *= growth
        x.append(x[-1] + h)
    x = np.array(x)
    if not exact:
        return x
    x = x[x < total_mm * (1 - 1e-9)]
    if len(x) > 2 and total_mm - x[-1] < 0.5 * (x[-1] - x[-2]) and x[-1] > fine_len_mm + 1e-9:
        x = x[:-1]
    return np.r_[x, total_mm]


# --------------------------------------------------------------------------- line-load deflection (thesis 6.2.1)
WATERBED_PER_BEAM = 8.0 / 3.0
"""Lw / Lb at which the waterbed and beam profiles agree to first order near the load (thesis 6.2.1)."""

def waterbed_deflection(x_mm, d0_mm, Lw_mm):
    """Waterbed model (Srinivasan 1989, thesis eq. 6.1): a membrane enclosing an incompressible
    fluid, line load at x = 0: delta = d0 [3 (x/Lw)^2 - 4 (x/Lw) + 1] for 0 <= |x| <= Lw, 0 beyond
    (the membrane's attachment). Deflection positive into the finger [mm]; it crosses zero at
    Lw/3 and bulges out (negative) on Lw/3 < |x| < Lw."""
    s = np.abs(np.asarray(x_mm, dtype=float)) / Lw_mm
    return np.where(s <= 1.0, d0_mm * (3 * s**2 - 4 * s + 1), 0.0)


def beam_deflection(x_mm, d0_mm, Lb_mm):
    """Cantilever beam of length Lb clamped at Lb, its free end (the load, x = 0) displaced d0
    (thesis eq. 6.2): delta = d0 [0.5 (x/Lb)^3 - 1.5 (x/Lb) + 1] for |x| <= Lb, 0 beyond [mm]."""
    s = np.abs(np.asarray(x_mm, dtype=float)) / Lb_mm
    return np.where(s <= 1.0, d0_mm * (0.5 * s**3 - 1.5 * s + 1), 0.0)


# --------------------------------------------------------------------------- standard linear solid
def sls_relaxation(t_s, g_inf, tau_s):
    """Relaxation modulus of a standard linear solid over its instantaneous one, g(t) = g_inf +
    (1 - g_inf) exp(-t / tau): the response to a unit step strain at t = 0 (t_s >= 0, s)."""
    t = np.asarray(t_s, float)
    return g_inf + (1.0 - g_inf) * np.exp(-t / tau_s)


def sls_creep(t_s, g_inf, tau_s):
    """Creep compliance of a standard linear solid times its instantaneous modulus, J(t) G0 =
    1 / g_inf - (1 / g_inf - 1) exp(-g_inf t / tau): the strain under a unit step stress at t = 0
    over the instantaneous strain (retardation time tau / g_inf)."""
    t = np.asarray(t_s, float)
    return 1.0 / g_inf - (1.0 / g_inf - 1.0) * np.exp(-g_inf * t / tau_s)


def sls_ramp_hold(t_s, ramp_s, g_inf, tau_s):
    """Stress of a standard linear solid under a strain ramped linearly from 0 at t = 0 to 1 at
    ramp_s and held, over the instantaneous modulus: (1 / ramp_s) int_0^min(t, ramp_s) g(t - s) ds."""
    return prony_ramp_hold(t_s, ramp_s, g_inf, [1.0 - g_inf], [tau_s])


def series_sls_relaxation(t_s, thickness_mm, E_MPa, g_inf, tau_s):
    """Stress [MPa] of standard linear solids in series (layers of thickness h_L, instantaneous
    modulus E_L, relaxed fraction g_inf_L, relaxation time tau_L; a stack compressed in uniaxial
    strain) after a unit step of the total shortening at t = 0 (t_s >= 0, s). Each layer is a
    spring E_L g_inf_L beside a Maxwell arm (E_L (1 - g_inf_L), tau_L) whose stress q_L obeys
    dq_L/dt = E_L (1 - g_inf_L) de_L/dt - q_L / tau_L; the stress sigma = E_L g_inf_L e_L + q_L is
    the same in every layer and sum h_L e_L = 1. Eliminating the strains leaves dq/dt = A q, solved
    by the matrix exponential from the instantaneous (all springs) state; one layer gives
    `sls_relaxation` times E."""
    from scipy.linalg import expm

    h, E, ginf, tau = (np.asarray(v, float) for v in (thickness_mm, E_MPa, g_inf, tau_s))
    c = 1.0 / np.sum(h / (E * ginf))
    # strain of each layer from q (sigma = E g_inf e + q equal, sum h e = 1): e = P q + r
    P = (np.outer(1.0 / (E * ginf), c * h / (E * ginf)) - np.diag(1.0 / (E * ginf)))
    r = c / (E * ginf)
    # dq/dt = E (1 - g_inf) P dq/dt - q / tau  ->  (I - D P) dq/dt = -q / tau
    D = np.diag(E * (1.0 - ginf))
    A = np.linalg.solve(np.eye(len(h)) - D @ P, -np.diag(1.0 / tau))
    sigma0 = 1.0 / np.sum(h / E)
    q0 = E * (1.0 - ginf) * sigma0 / E
    t = np.atleast_1d(np.asarray(t_s, float))
    q = np.stack([expm(A * tk) @ q0 for tk in t])
    e = q @ P.T + r
    out = (E * ginf * e + q)[:, 0]
    return out.reshape(np.shape(t_s))


def series_sls_creep(t_s, thickness_mm, E_MPa, g_inf, tau_s):
    """Total shortening [mm] of the stack of `series_sls_relaxation` under a unit step of stress
    [MPa] at t = 0: the layers' strains add, sum_L h_L J_L(t) with J_L = `sls_creep` / E_L."""
    t = np.asarray(t_s, float)
    return sum(h * sls_creep(t, gi, tau) / E for h, E, gi, tau in zip(thickness_mm, E_MPa, g_inf, tau_s))


def prony_ramp_hold(t_s, ramp_s, g_inf, g, tau_s):
    """The same for a Prony series g(t) = g_inf + sum_i g_i exp(-t / tau_i) (g, tau_s: (N,)):
    (g_inf min(t, t_r) + sum_i g_i tau_i (e^-(t - min(t, t_r))/tau_i - e^-t/tau_i)) / t_r. Also
    the force of a flat punch on a block, whose elastic force is proportional to its depth, over
    its elastic force at the end of the ramp."""
    t = np.asarray(t_s, float)
    u = np.minimum(t, ramp_s)[..., None]
    g, tau = np.asarray(g, float), np.asarray(tau_s, float)
    terms = (g * tau * (np.exp(-(t[..., None] - u) / tau) - np.exp(-t[..., None] / tau))).sum(axis=-1)
    return (g_inf * u[..., 0] + terms) / ramp_s


# --------------------------------------------------------------------------- flat punch (Sneddon 1946)
def sneddon_punch_force_N(radius_mm, depth_mm, E_MPa, nu):
    """Rigid flat circular punch of radius a pushed depth d into an elastic half-space:
    P = 2 a E d / (1 - nu^2) [N] (Sneddon 1946; Johnson 1985, chapter 3). The contact
    pressure is P / (2 pi a sqrt(a^2 - r^2)), singular at the punch edge."""
    return 2.0 * np.asarray(radius_mm, float) * E_MPa * np.asarray(depth_mm, float) / (1.0 - nu * nu)


def sneddon_punch_stress_zz_MPa(r_mm, z_mm, radius_mm, force_N):
    """Vertical (normal to the surface) stress under a rigid flat circular punch of radius a
    carrying force P, at distance r from the axis and depth z >= 0 [MPa], compression positive
    (Sneddon 1946, as TouchSim's `circ_load_vert_stress`):

        xi = z / a, rho = r / a, R = sqrt((rho^2 + xi^2 - 1)^2 + 4 xi^2),
        theta = arctan(1 / xi), phi = arctan2(2 xi, rho^2 + xi^2 - 1),
        J01 = sin(phi / 2) / sqrt(R),  J02 = sqrt(1 + xi^2) sin(3 phi / 2 - theta) / R^1.5,
        sigma_z = P / (2 pi a^2) (J01 + xi J02).

    On the axis this is P / (2 pi a^2) (1 + 3 xi^2) / (1 + xi^2)^2 (it tends to the punch pressure
    P / (2 pi a^2) at the surface and to Boussinesq's 3 P / (2 pi z^2) at depth). At z = 0 it is
    the contact pressure under the punch (inf on its edge) and 0 outside. Vectorised over r, z
    (broadcast); in the project's axes (surface y = 0, body y < 0) it is -sigma_yy at depth z = -y."""
    a = float(radius_mm)
    xi = np.asarray(z_mm, float) / a
    rho = np.asarray(r_mm, float) / a
    if np.any(xi < 0) or np.any(rho < 0):
        raise ValueError("r and z must be >= 0 (z is the depth below the surface)")
    with np.errstate(divide="ignore", invalid="ignore"):
        s = rho**2 + xi**2 - 1.0
        R = np.sqrt(s**2 + 4.0 * xi**2)
        theta = np.arctan2(1.0, xi)                     # arctan(1 / xi), pi / 2 at the surface
        phi = np.arctan2(2.0 * xi, s)
        J01 = np.sin(phi / 2.0) / np.sqrt(R)
        J02 = np.sqrt(1.0 + xi**2) * np.sin(1.5 * phi - theta) / R**1.5
        out = force_N / (2.0 * np.pi * a * a) * (J01 + xi * J02)
        surface = (xi == 0) & (rho != 1)                  # xi J02 -> 0; phi = pi inside (also for z = -0.0)
        if np.any(surface):
            inside = force_N / (2.0 * np.pi * a * a) / np.sqrt(np.abs(1.0 - rho**2))
            out = np.where(surface, np.where(rho < 1, inside, 0.0), out)
    return np.where((xi == 0) & (rho == 1), np.inf, out)

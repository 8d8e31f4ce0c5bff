"""Axisymmetric surface diffusion, parametric FEM (Barrett-Garcke-Nurnberg type).

Generating curve X=(r,z), piecewise linear, nodes 0..J.  Unknowns per step:
kappa^{m+1} (kappa = kappa_S, sum of principal curvatures with kappa_S nu = Lap_S id,
i.e. kappa = -H, H=2/R for a sphere) and X^{m+1}.

   < r^m (X^{m+1}-X^m)/dt . nu^m , chi >_W  -  < r^m d_s kappa^{m+1}, d_s chi > = 0
   < r^m kappa^{m+1} nu^m , eta >_W + < r^m d_s X^{m+1}, d_s eta > + < eta.e1 , 1 > = 0

i.e. V = -Lap_S kappa = +Lap_S H  (area decreasing, volume preserving surface diffusion).
<.,.>_W : "lumped" in the unknown nodal values, but with exact r-weighted integrals
W_i = int r^m phi_i nu^m ds, so that sum_i W_i.dX_i = int r^m dX.nu^m ds exactly
(first variation of the discrete enclosed volume -> volume conserved to O(dX^2)).
Endpoints: 'axis' (r=0 fixed) or 'mirror' (z fixed, symmetry plane).
"""
import os
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np
from scipy.linalg import solve_banded


def volume(X):
    r, z = X[:, 0], X[:, 1]
    dz = z[1:] - z[:-1]
    return np.pi * np.sum(dz * (r[:-1]**2 + r[:-1]*r[1:] + r[1:]**2) / 3.0)


def area(X):
    r = X[:, 0]
    h = np.linalg.norm(np.diff(X, axis=0), axis=1)
    return np.pi * np.sum(h * (r[:-1] + r[1:]))


def step(X, dt, bc=('axis', 'axis'), implicit_e1=True):
    J = X.shape[0] - 1
    n = 3 * (J + 1)
    e = X[1:] - X[:-1]
    h = np.sqrt((e**2).sum(1))
    tau = e / h[:, None]
    nu = np.stack([tau[:, 1], -tau[:, 0]], 1)      # outward for bottom->top, r>0 curve
    r = X[:, 0]
    ra, rb = r[:-1], r[1:]
    Wa = (h * (2*ra + rb) / 6.0)[:, None] * nu
    Wb = (h * (ra + 2*rb) / 6.0)[:, None] * nu
    W = np.zeros((J + 1, 2))
    W[:-1] += Wa
    W[1:] += Wb
    c = (ra + rb) / (2.0 * h)                         # r-weighted stiffness
    f = np.zeros(J + 1)
    f[:-1] += h / 2
    f[1:] += h / 2
    # banded matrix (l=u=3)
    BW = 4
    ab = np.zeros((2*BW + 1, n))
    def add(rows, cols, vals):
        np.add.at(ab, (BW + rows - cols, cols), vals)
    ia = np.arange(J)          # left node of element
    ib = ia + 1
    for comp, scale in ((0, -dt), (1, 1.0), (2, 1.0)):
        # stiffness in rows/cols of the same component
        add(3*ia + comp, 3*ia + comp, scale * c)
        add(3*ib + comp, 3*ib + comp, scale * c)
        add(3*ia + comp, 3*ib + comp, -scale * c)
        add(3*ib + comp, 3*ia + comp, -scale * c)
    if implicit_e1:
        # <eta.e1, |X^{m+1}_rho|> linearised as (X^{m+1}_b - X^{m+1}_a).tau^m / 2 per endpoint
        for i_ in (ia, ib):
            for cc in (0, 1):
                add(3*i_ + 1, 3*ib + 1 + cc, 0.5 * tau[:, cc])
                add(3*i_ + 1, 3*ia + 1 + cc, -0.5 * tau[:, cc])
    nodes = np.arange(J + 1)
    add(3*nodes, 3*nodes + 1, W[:, 0])
    add(3*nodes, 3*nodes + 2, W[:, 1])
    add(3*nodes + 1, 3*nodes, W[:, 0])
    add(3*nodes + 2, 3*nodes, W[:, 1])
    # rhs
    def Bmul(v):
        out = np.zeros(J + 1)
        d = c * (v[:-1] - v[1:])
        out[:-1] += d
        out[1:] -= d
        return out
    rhs = np.zeros(n)
    rhs[1::3] = -Bmul(X[:, 0]) - f
    rhs[2::3] = -Bmul(X[:, 1])
    # boundary conditions
    for node, kind in ((0, bc[0]), (J, bc[1])):
        row = 3*node + (1 if kind == 'axis' else 2)
        for off in range(-BW, BW + 1):
            col = row + off
            if 0 <= col < n:
                ab[BW + row - col, col] = 0.0
        ab[BW, row] = 1.0
        rhs[row] = 0.0
    u = solve_banded((BW, BW), ab, rhs, overwrite_ab=True, overwrite_b=True,
                     check_finite=False)
    kappa = u[0::3]
    dX = np.stack([u[1::3], u[2::3]], 1)
    return X + dX, kappa


def resample_polyline(P, J, corners=None):
    """Resample polyline P uniformly by arclength into J elements.
    If corners (indices of P) given, keep them as nodes, distributing elements
    proportionally to segment lengths."""
    if corners is None:
        corners = [0, len(P) - 1]
    out = []
    seglen = []
    for a, b in zip(corners[:-1], corners[1:]):
        Q = P[a:b+1]
        seglen.append(np.sum(np.linalg.norm(np.diff(Q, axis=0), axis=1)))
    seglen = np.array(seglen)
    nseg = np.maximum(1, np.round(J * seglen / seglen.sum()).astype(int))
    nseg[np.argmax(nseg)] += J - nseg.sum()
    for k, (a, b) in enumerate(zip(corners[:-1], corners[1:])):
        Q = P[a:b+1]
        s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))])
        si = np.linspace(0, s[-1], nseg[k] + 1)
        pts = np.stack([np.interp(si, s, Q[:, 0]), np.interp(si, s, Q[:, 1])], 1)
        out.append(pts if k == 0 else pts[1:])
    X = np.concatenate(out)
    X[0, 0] = 0.0 if P[0, 0] == 0 else X[0, 0]
    return X


def rod(J, L, r0, round_radius=0.0):
    if round_radius <= 0:
        P = np.array([[0, -L/2], [r0, -L/2], [r0, L/2], [0, L/2]], float)
        return resample_polyline(P, J, corners=[0, 1, 2, 3])
    rc = round_radius
    th = np.linspace(0, np.pi/2, 200)
    c1 = np.stack([r0 - rc + rc*np.sin(th), -L/2 + rc - rc*np.cos(th)], 1)
    c2 = np.stack([r0 - rc + rc*np.cos(th), L/2 - rc + rc*np.sin(th)], 1)
    P = np.concatenate([[[0, -L/2]], c1, c2, [[0, L/2]]])
    return resample_polyline(P, J)


def neck(X):
    """Smallest interior local minimum of r along the curve (parabolic refinement).
    Returns (rmin, zmin) or (nan, nan) if no interior minimum."""
    r = X[:, 0]
    i = np.arange(1, len(r) - 1)
    m = (r[i] <= r[i-1]) & (r[i] <= r[i+1])
    # ignore minima within 2 nodes of the axis ends
    m &= (i > 2) & (i < len(r) - 3)
    if not m.any():
        return np.nan, np.nan
    ii = i[m]
    k = ii[np.argmin(r[ii])]
    r0, r1, r2 = r[k-1], r[k], r[k+1]
    den = r0 - 2*r1 + r2
    if den > 1e-14:
        d = 0.5 * (r0 - r2) / den
        rm = r1 - 0.25 * (r0 - r2) * d
        zm = X[k, 1] + d * 0.5 * (X[k+1, 1] - X[k-1, 1])
    else:
        rm, zm = r1, X[k, 1]
    return rm, zm


# ---------------------------------------------------------------- remeshing
from scipy.interpolate import CubicSpline


def principal_curv(X):
    """nodal principal curvature magnitude K = sqrt(kc^2 + kaz^2)."""
    e = np.diff(X, axis=0)
    h = np.linalg.norm(e, axis=1)
    tau = e / h[:, None]
    ang = np.arctan2(tau[:, 1], tau[:, 0])
    dang = np.angle(np.exp(1j * np.diff(ang)))
    J = len(X) - 1
    kc = np.zeros(J + 1)
    kc[1:-1] = dang / (0.5 * (h[:-1] + h[1:]))
    kc[0], kc[-1] = kc[1], kc[-2]
    nu = np.stack([tau[:, 1], -tau[:, 0]], 1)
    nv = np.zeros((J + 1, 2)); nv[:-1] += nu; nv[1:] += nu
    nv /= np.linalg.norm(nv, axis=1)[:, None]
    kaz = np.zeros(J + 1)
    kaz[1:-1] = nv[1:-1, 0] / X[1:-1, 0]
    kaz[0], kaz[-1] = kc[0], kc[-1]
    return np.sqrt(kc**2 + kaz**2), nv


def density(X, a):
    K, _ = principal_curv(X)
    rho = np.sqrt(1.0 + (a * K)**2)
    # light smoothing + limit growth between neighbours
    for _ in range(3):
        rho[1:-1] = 0.25 * rho[:-2] + 0.5 * rho[1:-1] + 0.25 * rho[2:]
    return rho


def mesh_quality(X, a):
    h = np.linalg.norm(np.diff(X, axis=0), axis=1)
    rho = density(X, a)
    w = h * 0.5 * (rho[:-1] + rho[1:])
    q = w / w.mean()
    return q.max(), q.min()


def remesh(X, a, bc=('axis', 'axis')):
    J = len(X) - 1
    V0 = volume(X)
    h = np.linalg.norm(np.diff(X, axis=0), axis=1)
    s = np.concatenate([[0], np.cumsum(h)])
    rho = density(X, a)
    csr = CubicSpline(s, X[:, 0], bc_type=('natural', 'natural'))
    csz = CubicSpline(s, X[:, 1], bc_type=((1, 0.0), (1, 0.0)))
    # fine sampling for equidistribution
    sf = np.linspace(0, s[-1], 20 * J + 1)
    rf = np.interp(sf, s, rho)
    M = np.concatenate([[0], np.cumsum(0.5 * (rf[1:] + rf[:-1]) * np.diff(sf))])
    snew = np.interp(np.linspace(0, M[-1], J + 1), M, sf)
    Xn = np.stack([csr(snew), csz(snew)], 1)
    if bc[0] == 'axis': Xn[0, 0] = 0.0
    if bc[1] == 'axis': Xn[-1, 0] = 0.0
    # volume correction by a uniform normal shift
    _, nv = principal_curv(Xn)
    for _ in range(2):
        dV = V0 - volume(Xn)
        delta = dV / area(Xn)
        sh = delta * nv
        if bc[0] == 'axis': sh[0, 0] = 0
        if bc[1] == 'axis': sh[-1, 0] = 0
        Xn = Xn + sh
    return Xn

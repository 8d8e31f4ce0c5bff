import os, sys, time, json
os.environ["OMP_NUM_THREADS"]="1"; os.environ["OPENBLAS_NUM_THREADS"]="1"
import numpy as np
from sd_axi import *

def run(J, r0, dt0, L=8.0, rround=0.0, frac=None, rstop=0.02, tmax=20.0, verbose=False,
        save=None, a=0.3, qmax=1.6, do_remesh=True, remesh_below=0.8):
    if frac is None: frac = 5.0 * dt0        # max relative neck change per step
    X = rod(J, L, r0, rround)
    if do_remesh and rround > 0: X = remesh(X, a)
    V0 = volume(X); t = 0.0; n = 0; nrem = 0; dVrem = 0.0
    hist = []
    dt = dt0 * 1e-3
    t0 = time.time(); rn, zn = neck(X); rdot = 0.0
    while t < tmax:
        dt = min(dt0, max(dt0 * 1e-3, 10.0 * dt0 * t))
        if np.isfinite(rn) and rdot < 0: dt = min(dt, frac * rn / (-rdot))
        Xold = X
        X, kap = step(X, dt); t += dt; n += 1
        rn_new, zn = neck(X)
        rdot = (rn_new - rn) / dt if np.isfinite(rn_new) and np.isfinite(rn) else 0.0
        rn = rn_new
        if do_remesh and rn < remesh_below * r0:
            qM, qm = mesh_quality(X, a)
            if qM > qmax or qm < 1.0 / qmax:
                Vb = volume(X); X = remesh(X, a); nrem += 1
                dVrem += volume(X) - Vb  # (~0 by construction)
                rn, zn = neck(X)
        hist.append((t, rn, abs(zn) if np.isfinite(zn) else np.nan, X[-1, 1], volume(X)))
        if verbose and n % 5000 == 0:
            hh = np.linalg.norm(np.diff(X, axis=0), axis=1)
            print(f"n={n} t={t:.5f} dt={dt:.2e} rneck={rn:.4f} zneck={zn:.3f} tip={X[-1,1]:.3f} dV={volume(X)/V0-1:.2e} hmax/hmin={hh.max()/hh.min():.2f} nrem={nrem} cpu={time.time()-t0:.0f}s", flush=True)
        if np.isfinite(rn) and rn < rstop: break
    hist = np.array(hist)
    if save: np.savez(save, hist=hist, X=X)
    hh = np.linalg.norm(np.diff(X, axis=0), axis=1)
    res = dict(J=J, r0=r0, dt0=dt0, frac=frac, rround=rround, remesh=do_remesh, tstop=t,
               rstop=float(rn), zneck=float(abs(zn)), dV=float(volume(X)/V0 - 1),
               steps=n, nrem=nrem, hmin=float(hh.min()), hratio=float(hh.max()/hh.min()),
               cpu=time.time() - t0)
    if rn < rstop:
        for hi in (0.05, 0.1):
            sel = hist[:, 1] < hi
            p = np.polyfit(hist[sel, 0], hist[sel, 1]**4, 1)
            res[f"tstar_fit{hi}"] = float(-p[1] / p[0])
            res[f"C_fit{hi}"] = float((-p[0])**0.25)
    return res, hist, X

if __name__ == "__main__":
    J = int(sys.argv[1]); r0 = float(sys.argv[2]); dt0 = float(sys.argv[3])
    rr = float(sys.argv[4]) if len(sys.argv) > 4 else 0.0
    rm = (sys.argv[5] != '0') if len(sys.argv) > 5 else True
    tag = f"J{J}_r{r0:.4f}_dt{dt0:g}_rr{rr:g}_rm{int(rm)}"
    res, hist, X = run(J, r0, dt0, rround=rr, do_remesh=rm, verbose=True, save=f"out_{tag}.npz")
    print(json.dumps(res))
    with open("rod_pinch_results.jsonl", "a") as fh: fh.write(json.dumps(res) + "\n")

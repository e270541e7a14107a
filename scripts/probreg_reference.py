#!/usr/bin/python3
"""Reference numbers from the Python library probreg on a frozen regbench pair file.

Runs probreg's rigid CPD, GMMReg, SVR and FilterReg (the settings the OGMM paper used:
probreg's defaults) on every pair of a regbench pair file and writes one JSONL row per
(pair, method) in regbench's result format, with the metrics of docs/metrics.md
computed here (scipy as_euler('zyx'), lower case, no wrapping), then prints
a summary per method. This file contains no probreg code: probreg is imported from
--probreg-path (a checkout with its C++ extensions built in place) or from PYTHONPATH.

Run it with Debian's interpreter (/usr/bin/python3); see docs/probreg-equivalence.md.

    /usr/bin/python3 scripts/probreg_reference.py --pairs /tmp/eq20.h5 \
        --probreg-path /tmp/probreg-src --out data/reference/probreg_partial20_seed1.jsonl

Nondeterminism: sklearn's GaussianMixture (k-means++ init) draws from numpy's global
RandomState and probreg's IFGT k-center clustering draws from the C library's rand().
Before every call both are seeded from (--seed, pair index), so a row is reproducible;
--seeds 0,1,2 repeats the whole run with several seeds to show the spread.
"""

import argparse
import ctypes
import json
import math
import os
import platform
import statistics
import sys
import time

# Single-threaded numerics for timing (probreg's README measures with OMP_NUM_THREADS=1).
# Set before numpy is imported; --threads overrides.
def _set_threads_from_argv():
    threads = "1"
    for i, a in enumerate(sys.argv):
        if a == "--threads" and i + 1 < len(sys.argv):
            threads = sys.argv[i + 1]
        elif a.startswith("--threads="):
            threads = a.split("=", 1)[1]
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = threads


_set_threads_from_argv()

import h5py  # noqa: E402
import numpy as np  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

kFormatName = "regbench-pairs"
kCcdClip = 0.1
kAllMethods = ("cpd", "cpd-noscale", "gmmreg", "svr", "filterreg", "gmmreg-direct", "svr-direct")
kDefaultMethods = ("cpd", "gmmreg", "svr", "filterreg")


# ---------------------------------------------------------------- pair file -----------


def _attr_str(obj, name, where):
    if name not in obj.attrs:
        raise ValueError(f"{where}: missing attribute '{name}'")
    v = obj.attrs[name]
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.ndarray) and v.dtype.kind == "S":
        return v.tobytes().decode().rstrip("\0")
    return str(v)


def _cloud(group, name, where):
    if name not in group:
        raise ValueError(f"{where}: missing dataset '{name}'")
    a = np.asarray(group[name], dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{where}: {name} must be N x 3, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{where}: {name} has non-finite coordinates")
    return a


def read_pair_file(path):
    """Reads a regbench pair file (schema: protocols/pair_file.cpp)."""
    if not os.path.exists(path):
        raise FileNotFoundError(f"{path}: no such file")
    with h5py.File(path, "r") as f:
        if _attr_str(f, "format", path) != kFormatName:
            raise ValueError(f"{path}: not a regbench pair file (no format='{kFormatName}')")
        n = int(f.attrs["num_pairs"])
        provenance = json.loads(_attr_str(f, "provenance", path))
        pairs = []
        for k in range(n):
            where = f"{path}: pair {k}"
            name = f"/pairs/{k:06d}"
            if name not in f:
                raise ValueError(f"{where}: missing group {name}")
            g = f[name]
            T = np.asarray(g["T_gt"], dtype=np.float64) if "T_gt" in g else None
            if T is None or T.shape != (4, 4):
                raise ValueError(f"{where}: T_gt must be 4 x 4")
            pairs.append(
                {
                    "source": _cloud(g, "source", where),
                    "target": _cloud(g, "target", where),
                    "T_gt": T,
                    "shape": _attr_str(g, "shape", where) if "shape" in g.attrs else "",
                    "category": _attr_str(g, "category", where) if "category" in g.attrs else "",
                }
            )
    return provenance, pairs


# ---------------------------------------------------------------- metrics -------------


def rotation_part(T):
    """R of T = [sR t]: the scale (cube root of det) is divided out."""
    sR = T[:3, :3]
    s = np.cbrt(np.linalg.det(sR))
    return sR / s, s


def euler_zyx_deg(R):
    return Rotation.from_matrix(R).as_euler("zyx", degrees=True)


def euler_zyx_deg_of_block(M):
    """Euler zyx (deg) read off a 3x3 block as is, the way regbench's C++ metrics do
    (core/transform.cpp); differs from euler_zyx_deg only when M = s*R with s != 1."""
    b = math.asin(min(1.0, max(-1.0, -M[2, 0])))
    return np.degrees([math.atan2(M[1, 0], M[0, 0]), b, math.atan2(M[2, 1], M[2, 2])])


def chamfer(a, b, clip=kCcdClip):
    d_ab = cKDTree(b).query(a)[0]
    d_ba = cKDTree(a).query(b)[0]
    return {
        "ccd": float(np.minimum(d_ab, clip).mean() + np.minimum(d_ba, clip).mean()),
        "chamfer": float(np.mean(d_ab**2) + np.mean(d_ba**2)),
        "ccd_within_clip": bool(d_ab.mean() < clip and d_ba.mean() < clip),
    }


def pair_metrics(T_gt, T_est, source, target):
    """Metrics of docs/metrics.md: scipy as_euler('zyx') differences without wrapping."""
    R_gt, _ = rotation_part(T_gt)
    R_est, _ = rotation_part(T_est)
    dr = np.abs(euler_zyx_deg(R_gt) - euler_zyx_deg(R_est))
    dt = T_gt[:3, 3] - T_est[:3, 3]
    cos = np.clip((np.trace(R_gt.T @ R_est) - 1.0) / 2.0, -1.0, 1.0)
    m = {
        "mae_r": float(dr.mean()),
        "mae_t": float(np.abs(dt).mean()),
        "mse_r": float(np.mean(dr**2)),
        "mse_t": float(np.mean(dt**2)),
        "rre": float(np.degrees(np.arccos(cos))),
        "rte": float(np.linalg.norm(dt)),
    }
    moved = source @ T_est[:3, :3].T + T_est[:3, 3]
    m.update(chamfer(moved, target))
    return m


# ---------------------------------------------------------------- probreg calls --------


class _MinimizeRecorder:
    """Wraps scipy.optimize.minimize as probreg.l2dist_regs sees it, keeping the last
    OptimizeResult (probreg's registration_gmmreg/svr return only the transform)."""

    def __init__(self, module):
        self.module = module
        self.original = module.minimize
        self.last = None
        module.minimize = self

    def __call__(self, *args, **kwargs):
        self.last = self.original(*args, **kwargs)
        return self.last


class _DenseGaussTransform:
    """Exact Gauss transform, sum_j w_j exp(-|x_i - s_j|^2 / h^2), with the interface of
    probreg.gauss_transform.GaussTransform. The "-direct" variants put it in place of IFGT
    (eps 1e-4, random k-center clustering) so that the sums match regbench's exact ones."""

    def __init__(self, source, h, eps=1.0e-4, sw_h=0.01):
        self._source = np.asarray(source, dtype=np.float64)
        self._h2 = float(h) * float(h)

    def compute(self, target, weights=None):
        from scipy.spatial.distance import cdist

        k = np.exp(-cdist(np.asarray(target, dtype=np.float64), self._source, "sqeuclidean")
                   / self._h2)
        if weights is None:
            weights = np.ones(self._source.shape[0])
        weights = np.asarray(weights)
        if weights.ndim == 1:
            return k @ weights
        if weights.ndim == 2:
            return (k @ weights.T).T
        raise ValueError("weights.ndim must be 1 or 2.")


def _to_matrix(rot, t, scale=1.0):
    T = np.eye(4)
    T[:3, :3] = scale * np.asarray(rot, dtype=np.float64)
    T[:3, 3] = np.asarray(t, dtype=np.float64)
    return T


def make_runners(probreg, maxiter_cpd=50, tol_cpd=1e-3):
    """Method name -> (params, function(source, target) -> (T, iterations, stop, scale, extra))."""
    from probreg import cpd, filterreg, gauss_transform, l2dist_regs

    recorder = _MinimizeRecorder(l2dist_regs)

    def counter():
        calls = []
        return calls, (lambda tf: calls.append(1))

    def run_cpd(update_scale):
        params = {"tf_type_name": "rigid", "w": 0.0, "maxiter": maxiter_cpd, "tol": tol_cpd,
                  "update_scale": update_scale}

        def fn(source, target):
            calls, cb = counter()
            res = cpd.registration_cpd(source, target, "rigid", w=0.0, maxiter=maxiter_cpd,
                                       tol=tol_cpd, callbacks=[cb], update_scale=update_scale)
            tf = res.transformation
            n = len(calls)
            stop = "max_iterations" if n >= maxiter_cpd else "converged"
            extra = {"sigma2": float(res.sigma2), "q": float(res.q)}
            return _to_matrix(tf.rot, tf.t, tf.scale), n, stop, float(tf.scale), extra

        return params, fn

    def run_l2(kind, direct=False):
        if kind == "gmmreg":
            params = {"tf_type_name": "rigid", "sigma": 1.0, "delta": 0.9, "n_gmm_components": 800,
                      "use_estimated_sigma": True, "maxiter": 1, "opt_maxiter": 50, "opt_tol": 1e-3}
        else:
            params = {"tf_type_name": "rigid", "maxiter": 1, "tol": 1e-3, "opt_maxiter": 50,
                      "opt_tol": 1e-3, "sigma": 1.0, "delta": 0.9, "gamma": 0.5, "nu": 0.1,
                      "use_estimated_sigma": True}

        def fn(source, target):
            calls, cb = counter()
            recorder.last = None
            saved = gauss_transform.GaussTransform
            if direct:
                gauss_transform.GaussTransform = _DenseGaussTransform
            try:
                if kind == "gmmreg":
                    tf = l2dist_regs.registration_gmmreg(source, target, "rigid", callbacks=[cb])
                else:
                    tf = l2dist_regs.registration_svr(source, target, "rigid", callbacks=[cb])
            finally:
                gauss_transform.GaussTransform = saved
            r = recorder.last
            extra = {}
            stop = ""
            if r is not None:
                extra = {"bfgs_message": str(r.message), "bfgs_status": int(r.status),
                         "nfev": int(r.nfev), "fun": float(r.fun)}
                stop = "converged" if r.success else (
                    "max_iterations" if int(r.status) == 1 else "line_search_failed")
            if kind == "gmmreg":
                extra["n_gmm_components"] = min(800, int(source.shape[0] * 0.8))
            return _to_matrix(tf.rot, tf.t, tf.scale), len(calls), stop, float(tf.scale), extra

        if direct:
            params = dict(params, gauss_transform="direct")
        return params, fn

    def run_filterreg():
        params = {"sigma2": None, "update_sigma2": False, "w": 0.0, "objective_type": "pt2pt",
                  "maxiter": 50, "tol": 1e-3, "min_sigma2": 1e-4}

        def fn(source, target):
            calls, cb = counter()
            res = filterreg.registration_filterreg(source, target, callbacks=[cb])
            tf = res.transformation
            n = len(calls)
            if res.q is None and n == 0:
                stop = "empty_estep"
            else:
                stop = "max_iterations" if n >= 50 else "converged"
            extra = {"sigma2": float(res.sigma2), "q": None if res.q is None else float(res.q)}
            return _to_matrix(tf.rot, tf.t, tf.scale), n, stop, float(tf.scale), extra

        return params, fn

    return {
        "cpd": run_cpd(True),
        "cpd-noscale": run_cpd(False),
        "gmmreg": run_l2("gmmreg"),
        "svr": run_l2("svr"),
        "filterreg": run_filterreg(),
        "gmmreg-direct": run_l2("gmmreg", direct=True),
        "svr-direct": run_l2("svr", direct=True),
    }


def seed_everything(libc, seed, pair_index):
    """numpy's global RandomState (sklearn GaussianMixture init) and libc rand() (IFGT)."""
    np.random.seed([seed, pair_index])
    if libc is not None:
        libc.srand(ctypes.c_uint((seed * 1000003 + pair_index) & 0xFFFFFFFF))


# ---------------------------------------------------------------- main ----------------


def summarize(rows):
    by = {}
    for r in rows:
        by.setdefault((r["method"], r["probreg_seed"]), []).append(r)
    out = []
    for (method, seed), rs in by.items():
        ok = [r for r in rs if r["status"] == "ok"]
        out.append({
            "method": method,
            "seed": seed,
            "pairs": len(rs),
            "failed": len(rs) - len(ok),
            "mean_mae_r": statistics.fmean(r["metrics"]["mae_r"] for r in rs),
            "median_mae_r": statistics.median(r["metrics"]["mae_r"] for r in rs),
            "mean_mae_t": statistics.fmean(r["metrics"]["mae_t"] for r in rs),
            "mean_rre": statistics.fmean(r["metrics"]["rre"] for r in rs),
            "mean_ccd": statistics.fmean(r["metrics"]["ccd"] for r in rs),
            "median_seconds": statistics.median(r["seconds"] for r in rs),
            "mean_seconds": statistics.fmean(r["seconds"] for r in rs),
            "median_cpu_seconds": statistics.median(r["extra"]["cpu_seconds"] for r in rs),
            "mean_iterations": statistics.fmean(r["iterations"] for r in rs),
        })
    return out


def print_summary(summary, stream):
    hdr = (f"{'method':<22}{'seed':>5}{'pairs':>6}{'fail':>5}{'mae_r':>9}{'med_r':>9}"
           f"{'mae_t':>9}{'rre':>9}{'ccd':>8}{'med_s':>9}{'med_cpu':>9}{'iters':>7}")
    print(hdr, file=stream)
    for s in summary:
        print(f"{s['method']:<22}{s['seed']:>5}{s['pairs']:>6}{s['failed']:>5}"
              f"{s['mean_mae_r']:>9.3f}{s['median_mae_r']:>9.3f}{s['mean_mae_t']:>9.4f}"
              f"{s['mean_rre']:>9.3f}{s['mean_ccd']:>8.4f}{s['median_seconds']:>9.4f}"
              f"{s['median_cpu_seconds']:>9.4f}"
              f"{s['mean_iterations']:>7.1f}", file=stream)
    methods = sorted({s["method"] for s in summary})
    for m in methods:
        vals = [s["mean_mae_r"] for s in summary if s["method"] == m]
        if len(vals) > 1:
            print(f"spread over {len(vals)} seeds, {m}: mean mae_r min {min(vals):.3f} "
                  f"max {max(vals):.3f} (range {max(vals) - min(vals):.3f} deg)", file=stream)


def versions(probreg):
    import importlib
    out = {"python": platform.python_version(), "machine": platform.machine(),
           "processor": platform.processor(), "platform": platform.platform()}
    for mod in ("numpy", "scipy", "sklearn", "open3d", "transforms3d", "h5py"):
        try:
            out[mod] = importlib.import_module(mod).__version__
        except Exception as e:  # report, don't fail
            out[mod] = f"unavailable: {e}"
    out["probreg"] = getattr(probreg, "__version__", "?")
    out["probreg_path"] = os.path.dirname(probreg.__file__)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", required=True, help="regbench pair file (HDF5)")
    ap.add_argument("--out", required=True, help="JSONL output (written as OUT.part, then renamed)")
    ap.add_argument("--probreg-path", default=None,
                    help="folder that contains the probreg package (extensions built in place)")
    ap.add_argument("--methods", default=",".join(kDefaultMethods),
                    help=f"comma-separated subset of {','.join(kAllMethods)}")
    ap.add_argument("--seeds", default="0", help="comma-separated seeds; each repeats the run")
    ap.add_argument("--limit", type=int, default=0, help="only the first N pairs (0 = all)")
    ap.add_argument("--threads", default="1", help="OMP/BLAS threads (default 1)")
    ap.add_argument("--summary-out", default=None, help="also write the summary as JSON")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    for m in methods:
        if m not in kAllMethods:
            ap.error(f"--methods: unknown method '{m}' (known: {', '.join(kAllMethods)})")
    try:
        seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    except ValueError:
        ap.error(f"--seeds must be comma-separated integers, got '{args.seeds}'")
    if not seeds:
        ap.error("--seeds is empty")

    if args.probreg_path:
        if not os.path.isdir(os.path.join(args.probreg_path, "probreg")):
            ap.error(f"--probreg-path: no probreg package in '{args.probreg_path}'")
        sys.path.insert(0, os.path.abspath(args.probreg_path))
    import probreg

    provenance, pairs = read_pair_file(args.pairs)
    if args.limit > 0:
        pairs = pairs[: args.limit]
    runners = make_runners(probreg)
    data_tag = {  # as regbench's runner tags its rows
        "pairs_file": os.path.basename(args.pairs),
        "dataset": provenance.get("dataset", "unknown"),
        "protocol": provenance.get("protocol", "unknown"),
        "pairing": provenance.get("pairing", "unknown"),
        "seed": provenance.get("seed"),
    }
    libc = ctypes.CDLL(None)

    rows = []
    tmp = args.out + ".part"
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(tmp, "w") as out:
        for seed in seeds:
            for k, p in enumerate(pairs):
                for m in methods:
                    params, fn = runners[m]
                    seed_everything(libc, seed, k)
                    status, message = "ok", ""
                    T, iters, stop, scale, extra = np.eye(4), 0, "", 1.0, {}
                    t0 = time.perf_counter()
                    c0 = time.process_time()
                    try:
                        T, iters, stop, scale, extra = fn(p["source"], p["target"])
                    except Exception as e:  # a failed call is a row, not a crash
                        status, message = "failed", f"probreg-{m}: {type(e).__name__}: {e}"
                    seconds = time.perf_counter() - t0
                    cpu_seconds = time.process_time() - c0
                    if status == "ok" and not np.isfinite(T).all():
                        status, message = "failed", f"probreg-{m}: non-finite transform"
                    if status != "ok":
                        T = np.eye(4)
                    if abs(scale - 1.0) > 0.0:
                        # What mae_r would be if s*R were not divided out (see the doc).
                        d = euler_zyx_deg_of_block(p["T_gt"][:3, :3]) - euler_zyx_deg_of_block(
                            T[:3, :3])
                        extra["mae_r_on_sR_block"] = float(np.abs(d).mean())
                    # CPU time of this process: less disturbed than wall time on a busy machine.
                    extra["cpu_seconds"] = cpu_seconds
                    row = {
                        "pair": k,
                        "method": f"probreg-{m}",
                        "params": params,
                        "transform": T.tolist(),
                        "iterations": int(iters),
                        "stop_reason": stop,
                        "seconds": seconds,
                        "status": status,
                        "message": message,
                        "scale": scale,
                        "extra": extra,
                        "threads": int(args.threads),
                        "shape": p["shape"],
                        "category": p["category"],
                        "probreg_seed": seed,
                        "data": data_tag,
                        "metrics": pair_metrics(p["T_gt"], T, p["source"], p["target"]),
                    }
                    rows.append(row)
                    out.write(json.dumps(row) + "\n")
                    out.flush()
                    if not args.quiet:
                        print(f"[probreg] seed {seed} pair {k} {m}: mae_r "
                              f"{row['metrics']['mae_r']:.3f} deg, {seconds:.3f} s, {iters} it, "
                              f"{status}", file=sys.stderr)
    os.replace(tmp, args.out)

    summary = summarize(rows)
    print(f"# {args.pairs}: {len(pairs)} pairs, provenance {json.dumps(provenance)}")
    print_summary(summary, sys.stdout)
    if args.summary_out:
        with open(args.summary_out, "w") as f:
            json.dump({"pairs_file": args.pairs, "provenance": provenance,
                       "versions": versions(probreg), "threads": args.threads,
                       "summary": summary}, f, indent=1)
            f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

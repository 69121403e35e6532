#!/usr/bin/python3
"""The error a causal estimator could have had, beside the window's and the batch's.

usage: bench/causal_limit.py SKERRY DATASET OUT [--step S | --at T1,T2,...] [--config PRESET]
                             [--jobs N] [--reuse]

A batch smoother over the data up to time T, read at its last keyframe, is the best estimate
anything causal can make at T from the same data and models (a filter or a fixed-lag smoother
only approximates it; pipeline.h SmoothUntil is the same thing inside the library). For T every
S seconds (default 10) this runs `skerry smooth --until T` (the dataset cut at T by the library's
DatasetUntil: every stream, frame list and pose fix up to T) and
compares, at those instants, the error of that last keyframe with the window's (`skerry run`,
filtered: the estimate when the keyframe was newest) and the whole-run batch's: heading (the
body x axis, degrees clockwise from north, wrapped to (-180, 180]) and horizontal position (m).
Prints the RMS of each over all instants and the ratios, and the horizontal one-sigma each
claims (states.csv: hypot(sigma_px, sigma_py)) beside its error: a window whose sigma is wider
than the best causal estimate's is conservative against what its data could support. Slow by
design: one batch per instant (--jobs runs that many at once; --at names the instants, seconds
of the dataset's clock; --reuse keeps OUT/window and OUT/batch from an earlier call instead of
running them again).
"""
import argparse
import concurrent.futures
import os
import shutil
import subprocess

import numpy as np


def heading_deg(q):
    """Heading of the body x axis, clockwise from north, for rows of quaternions [x, y, z, w]."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    east = 1 - 2 * (y * y + z * z)
    north = 2 * (x * y + w * z)
    return np.degrees(np.arctan2(east, north))


def wrap(d):
    return np.remainder(d + 180.0, 360.0) - 180.0


def states(path):
    """t, heading (deg), east/north position (m) and horizontal one-sigma (m) of a skerry
    states.csv."""
    with open(path) as f:
        names = f.readline().strip().split(",")
    a = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    sigma = np.hypot(a[:, names.index("sigma_px")], a[:, names.index("sigma_py")])
    return a[:, 0], heading_deg(a[:, 4:8]), a[:, 1:3], sigma


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("skerry")
    p.add_argument("dataset")
    p.add_argument("out")
    p.add_argument("--step", type=float, default=10.0)
    p.add_argument("--config", default="default")
    p.add_argument("--at", default="")
    p.add_argument("--jobs", type=int, default=1)
    p.add_argument("--reuse", action="store_true")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    cfg = ["--config", a.config]
    win_dir, bat_dir = os.path.join(a.out, "window"), os.path.join(a.out, "batch")
    for command, out in (("run", win_dir), ("smooth", bat_dir)):
        if not (a.reuse and os.path.exists(os.path.join(out, "states.csv"))):
            run([a.skerry, command, "--dataset", a.dataset, "--out", out, "--overwrite"] + cfg)

    gt = np.loadtxt(os.path.join(a.dataset, "groundtruth.tum"), comments="#", ndmin=2)
    t_gt, h_gt = gt[:, 0], np.unwrap(np.radians(heading_deg(gt[:, 4:8])))

    def err(t, h, p):
        """Heading error (deg) and horizontal position error (m) at times t."""
        e_h = wrap(h - np.degrees(np.interp(t, t_gt, h_gt)))
        g = np.stack([np.interp(t, t_gt, gt[:, 1]), np.interp(t, t_gt, gt[:, 2])], axis=1)
        return e_h, np.linalg.norm(p - g, axis=1)

    t_w, h_w, p_w, s_w = states(os.path.join(win_dir, "states.csv"))
    t_b, h_b, p_b, s_b = states(os.path.join(bat_dir, "states.csv"))
    (eh_w, ep_w), (eh_b, ep_b) = err(t_w, h_w, p_w), err(t_b, h_b, p_b)
    t_first = max(t_w[0], t_b[0])
    if a.at:
        ends = np.array([float(x) for x in a.at.split(",")])
    else:
        ends = np.arange(t_first + a.step, min(t_w[-1], t_b[-1]), a.step)

    def causal(k):
        """The last keyframe of the batch over the data up to ends[k]: t, heading and position
        errors, horizontal sigma."""
        d = os.path.join(a.out, "cut%d" % k)
        shutil.rmtree(d, ignore_errors=True)
        try:
            run([a.skerry, "smooth", "--dataset", a.dataset, "--until", "%.9f" % ends[k],
                 "--out", os.path.join(d, "out"), "--overwrite"] + cfg)
        except subprocess.CalledProcessError:
            return None  # too early: the data up to ends[k] do not start an estimator yet
        t_c, h_c, p_c, s_c = states(os.path.join(d, "out", "states.csv"))
        e_h, e_p = err(t_c[-1:], h_c[-1:], p_c[-1:])
        shutil.rmtree(d, ignore_errors=True)
        return t_c[-1], e_h[0], e_p[0], s_c[-1]

    rows = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        for k, result in enumerate(pool.map(causal, range(len(ends)))):
            if result is None:
                print("t %8.2f s  no estimate from the data up to then" % ends[k], flush=True)
                continue
            t, e_h, e_p, s_c = result
            iw, ib = np.argmin(abs(t_w - t)), np.argmin(abs(t_b - t))
            rows.append((t, eh_w[iw], e_h, eh_b[ib], ep_w[iw], e_p, ep_b[ib], s_w[iw], s_c,
                         s_b[ib]))
            print("t %8.2f s  heading error  window %7.2f  causal batch %7.2f  whole batch %7.2f"
                  "   horizontal  window %7.2f  causal batch %7.2f  whole batch %7.2f m"
                  "   sigma  window %7.2f  causal batch %7.2f  whole batch %7.2f m" %
                  rows[-1], flush=True)
    r = np.array(rows)
    rms = np.sqrt(np.mean(r[:, 1:] ** 2, axis=0))
    print("RMS over %d instants: heading window %.3f deg, best causal %.3f deg, batch %.3f deg" %
          (len(r), rms[0], rms[1], rms[2]))
    print("  window / best causal %.2f, best causal / batch %.2f, window / batch %.2f" %
          (rms[0] / rms[1], rms[1] / rms[2], rms[0] / rms[2]))
    print("RMS over %d instants: horizontal window %.3f m, best causal %.3f m, batch %.3f m" %
          (len(r), rms[3], rms[4], rms[5]))
    print("  window / best causal %.2f, best causal / batch %.2f, window / batch %.2f" %
          (rms[3] / rms[4], rms[4] / rms[5], rms[3] / rms[5]))
    print("RMS over %d instants: horizontal sigma window %.3f m, best causal %.3f m, batch %.3f m"
          % (len(r), rms[6], rms[7], rms[8]))
    print("  window / best causal %.2f; error / sigma: window %.2f, best causal %.2f, batch %.2f" %
          (rms[6] / rms[7], rms[3] / rms[6], rms[4] / rms[7], rms[5] / rms[8]))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""The heading a causal estimator could have had, beside the window's and the batch's.

usage: bench/causal_limit.py SKERRY DATASET OUT [--step S] [--config PRESET]

A batch smoother over the data up to time T, read at its last keyframe, is the best estimate
anything causal can make at T from the same data and models (a filter or a fixed-lag smoother
only approximates it). For T every S seconds (default 10) this runs `skerry smooth` on the
dataset cut at T (imu.csv and gnss.csv rows up to T; an IMU + GNSS dataset) and compares, at
those instants, the heading error of that last keyframe with the window's (`skerry run`,
filtered: the estimate when the keyframe was newest) and the whole-run batch's. Prints the RMS
of each over all instants and the ratios. Heading: the body x axis, degrees clockwise from north,
errors wrapped to (-180, 180]. Slow by design: one batch per instant.
"""
import argparse
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
    """t and heading (deg) of a skerry states.csv."""
    a = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return a[:, 0], heading_deg(a[:, 4:8])


def cut(src, dst, t_end):
    """A copy of dataset `src` with imu.csv and gnss.csv rows up to t_end."""
    os.makedirs(dst, exist_ok=True)
    for name in os.listdir(src):
        path = os.path.join(src, name)
        if not os.path.isfile(path):
            continue
        if name in ("imu.csv", "gnss.csv"):
            with open(path) as f_in, open(os.path.join(dst, name), "w") as f_out:
                f_out.write(f_in.readline())
                for line in f_in:
                    if float(line.split(",", 1)[0]) > t_end:
                        break
                    f_out.write(line)
        else:
            shutil.copy(path, dst)


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("skerry")
    p.add_argument("dataset")
    p.add_argument("out")
    p.add_argument("--step", type=float, default=10.0)
    p.add_argument("--config", default="default")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    cfg = ["--config", a.config]
    win_dir, bat_dir = os.path.join(a.out, "window"), os.path.join(a.out, "batch")
    run([a.skerry, "run", "--dataset", a.dataset, "--out", win_dir, "--overwrite"] + cfg)
    run([a.skerry, "smooth", "--dataset", a.dataset, "--out", bat_dir, "--overwrite"] + cfg)

    gt = np.loadtxt(os.path.join(a.dataset, "groundtruth.tum"), comments="#", ndmin=2)
    t_gt, h_gt = gt[:, 0], np.unwrap(np.radians(heading_deg(gt[:, 4:8])))

    def err(t, h):
        return wrap(h - np.degrees(np.interp(t, t_gt, h_gt)))

    t_w, h_w = states(os.path.join(win_dir, "states.csv"))
    t_b, h_b = states(os.path.join(bat_dir, "states.csv"))
    e_w, e_b = err(t_w, h_w), err(t_b, h_b)
    rows = []
    t_first = max(t_w[0], t_b[0])
    for t_end in np.arange(t_first + a.step, min(t_w[-1], t_b[-1]), a.step):
        d = os.path.join(a.out, "cut")
        shutil.rmtree(d, ignore_errors=True)
        cut(a.dataset, os.path.join(d, "data"), t_end)
        run([a.skerry, "smooth", "--dataset", os.path.join(d, "data"), "--out",
             os.path.join(d, "out"), "--overwrite"] + cfg)
        t_c, h_c = states(os.path.join(d, "out", "states.csv"))
        t = t_c[-1]
        rows.append((t, e_w[np.argmin(abs(t_w - t))], err(t_c[-1:], h_c[-1:])[0],
                     e_b[np.argmin(abs(t_b - t))]))
        print("t %8.2f s  heading error  window %7.2f  causal batch %7.2f  whole batch %7.2f" %
              rows[-1], flush=True)
    r = np.array(rows)
    rms = np.sqrt(np.mean(r[:, 1:] ** 2, axis=0))
    print("RMS over %d instants: window %.3f deg, best causal %.3f deg, batch %.3f deg" %
          (len(r), rms[0], rms[1], rms[2]))
    print("window / best causal %.2f, best causal / batch %.2f, window / batch %.2f" %
          (rms[0] / rms[1], rms[1] / rms[2], rms[0] / rms[2]))


if __name__ == "__main__":
    main()

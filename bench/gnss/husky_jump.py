#!/usr/bin/env python3
"""The jump test on real data: Husky's IMU and GPS (../shared/data/husky, imported by
`skerry import --format husky`) with a jump injected into the GPS, the window with and without
`gnss.jump_test`, errors against the un-jumped fixes (the rover has no other ground truth).

usage: bench/gnss/husky_jump.py SKERRY HUSKY_DATASET OUT [--start 200] [--duration 20] [--east 14.5]
"""
import argparse, bisect, json, math, os, subprocess, sys

ap = argparse.ArgumentParser()
ap.add_argument("skerry"); ap.add_argument("dataset"); ap.add_argument("out")
ap.add_argument("--start", type=float, default=200.0)
ap.add_argument("--duration", type=float, default=20.0)
ap.add_argument("--east", type=float, default=14.5)
a = ap.parse_args()
os.makedirs(a.out, exist_ok=True)

# The jumped dataset: every file but gnss.csv linked, the fixes in [start, start + duration) moved east.
jd = os.path.join(a.out, "data")
os.makedirs(jd, exist_ok=True)
for f in os.listdir(a.dataset):
    dst = os.path.join(jd, f)
    if f != "gnss.csv" and not os.path.exists(dst):
        os.symlink(os.path.abspath(os.path.join(a.dataset, f)), dst)
lines = open(os.path.join(a.dataset, "gnss.csv")).read().splitlines()
t0 = float(lines[1].split(",")[0])
fixes, out = [], [lines[0]]
lat0 = float(lines[1].split(",")[1]); lon0 = float(lines[1].split(",")[2])
for l in lines[1:]:
    f = l.split(",")
    t, lat, lon = float(f[0]), float(f[1]), float(f[2])
    fixes.append((t - t0, (lon - lon0) * 111320.0 * math.cos(math.radians(lat0)), (lat - lat0) * 110950.0))
    if a.start <= t - t0 < a.start + a.duration:
        f[2] = repr(lon + a.east / (111320.0 * math.cos(math.radians(lat))))
    out.append(",".join(f))
open(os.path.join(jd, "gnss.csv"), "w").write("\n".join(out) + "\n")

# Errors against the original fixes (local east/north from the first fix; the dataset's origin).
def errors(states, lo, hi):
    rows = [l.split(",") for l in open(states).read().splitlines()[1:]]
    ts = [float(r[0]) - t0 for r in rows]
    d = []
    for t, e, n in fixes:
        i = bisect.bisect_left(ts, t)
        if lo <= t < hi and i < len(ts):
            d.append(math.hypot(float(rows[i][1]) - e, float(rows[i][2]) - n))
    return max(d), math.sqrt(sum(x * x for x in d) / len(d))

s, e = a.start, a.start + a.duration
print("| jump test | RMSE / max before (m) | during the jump | 60 s after it | back under 2 m (s after the jump) | refused as the jump | re-acquired on the receiver back |")
print("|---|---|---|---|---|---|---|")
for name in ("on", "off"):
    run = os.path.join(a.out, name)
    subprocess.run([a.skerry, "run", "--dataset", jd, "--set", "gnss.jump_test=" + ("true" if name == "on" else "false"),
                    "--out", run, "--overwrite", "-q"],
                   check=True, stderr=subprocess.DEVNULL)
    g = json.load(open(os.path.join(run, "summary.json")))["solver"]["gnss"]
    st = os.path.join(run, "states.csv")
    rows = [l.split(",") for l in open(st).read().splitlines()[1:]]
    ts = [float(r[0]) - t0 for r in rows]
    back = next((t - e for t, x, y in fixes if t >= e and
                 math.hypot(float(rows[min(bisect.bisect_left(ts, t), len(ts) - 1)][1]) - x,
                            float(rows[min(bisect.bisect_left(ts, t), len(ts) - 1)][2]) - y) < 2.0), float("nan"))
    b, d, f = errors(st, 0, s), errors(st, s, e), errors(st, e, e + 60)
    print(f"| {name} | {b[1]:.2f} / {b[0]:.2f} | {d[1]:.2f} / {d[0]:.2f} | {f[1]:.2f} / {f[0]:.2f} | {back:.1f} | {g['rejected_as_jump']} | {g['reacquired_back_from_jump']} |")

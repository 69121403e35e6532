#!/usr/bin/env python3
"""Heading error of a skerry run against ground truth from T0 seconds after its first estimate:
RMS, max, the RMS of the estimator's own heading 1-sigma and the heading ANEES (1 if
consistent). The "from 60 s" figures of docs/results.md, *Start-up on real platforms*.
Standard library only.

usage: heading_from.py RUN_DIR DATASET_DIR T0
  RUN_DIR      `skerry run --out` folder (states.csv)
  DATASET_DIR  the dataset (groundtruth.tum)
"""
import sys, math, csv, bisect
run, data, t0 = sys.argv[1], sys.argv[2], float(sys.argv[3])
def yaw(qx, qy, qz, qw):
    return math.atan2(2 * (qx * qy + qw * qz), 1 - 2 * (qy * qy + qz * qz))
gt = [list(map(float, l.split())) for l in open(data + '/groundtruth.tum') if l.strip() and not l.startswith('#')]
gts = [g[0] for g in gt]
rows = list(csv.DictReader(open(run + '/states.csv')))
tstart = float(rows[0]['t'])
e2 = []; s2 = []; n2 = []; mx = 0
for r in rows:
    t = float(r['t'])
    if t - tstart < t0: continue
    i = bisect.bisect_left(gts, t)
    if i == 0 or i >= len(gt): continue
    g = gt[i] if abs(gts[i] - t) < abs(gts[i-1] - t) else gt[i-1]
    e = yaw(*map(float, (r['qx'], r['qy'], r['qz'], r['qw']))) - yaw(*g[4:8])
    e = math.degrees(math.atan2(math.sin(e), math.cos(e)))
    s = float(r['sigma_heading_deg'])
    e2.append(e * e); s2.append(s * s); n2.append((e / s) ** 2); mx = max(mx, abs(e))
rms = lambda v: math.sqrt(sum(v) / len(v))
print(f"from {t0:.0f} s: heading RMS {rms(e2):.2f} deg (max {mx:.2f}), sigma RMS {rms(s2):.2f}, ANEES1 {sum(n2)/len(n2):.2f}, n {len(e2)}")

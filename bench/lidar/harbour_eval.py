#!/usr/bin/env python3
"""The table of bench/lidar/harbour_runs.sh: for each run, the window's horizontal position error
and heading error against the simulator's truth (RMSE and max), the largest error while a GNSS
jump is on and the jump's pull (for a `...-jump` run whose `...-drift` twin is in OUT: the largest
horizontal distance between the two estimates from the jump on; the twins' data differ only in the
jumped fixes, so this is what the jump moved the estimate by, apart from the error both share), and for a run with a GNSS outage to its end the error over the first and the last five
minutes of the outage (half of it when shorter); the LiDAR blocks accepted, rejected, re-acquired and flagged degenerate
(summary.json). With OUT/<run>.batch/ (skerry smooth) skerry's batch, and with OUT/<run>.baseline/
(bench/harbour_baseline.cc) prior work's pipeline, on the same data beside it. Standard library only."""
import bisect
import json
import math
import os
import sys


def tum(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith('#') or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            rows.append(v)
    return rows


def yaw(q):
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def events(path):
    out = []
    if os.path.exists(path):
        with open(path) as f:
            next(f)
            for line in f:
                a = line.strip().split(',')
                if len(a) >= 3:
                    out.append((float(a[0]), float(a[1]), a[2]))
    return out


def errors(gt, tr):
    """(t, horizontal error, heading error in degrees) at each estimate with a truth pose within
    11 ms."""
    times = [g[0] for g in gt]
    err = []
    for r in tr:
        i = bisect.bisect_left(times, r[0])
        near = [k for k in (i - 1, i) if 0 <= k < len(gt)]
        if not near:
            continue
        k = min(near, key=lambda k: abs(gt[k][0] - r[0]))
        if abs(gt[k][0] - r[0]) > 0.011:
            continue
        g = gt[k]
        h = math.hypot(r[1] - g[1], r[2] - g[2])
        d = (yaw(r[4:8]) - yaw(g[4:8])) * 180 / math.pi
        d = (d + 180) % 360 - 180
        err.append((r[0], h, d))
    return err


def pull(root, run, kind, ev):
    """The largest horizontal distance (m) between the estimate of `run` (a `...-jump` run) and
    that of its `...-drift` twin from the jump's start on, or None without a twin or a jump."""
    if not run.endswith('-jump'):
        return None
    twin = os.path.join(root, run[:-len('jump')] + 'drift' + kind, 'trajectory.tum')
    mine = os.path.join(root, run + kind, 'trajectory.tum')
    starts = [a for (a, b, k) in ev if k == 'jump']
    if not starts or not os.path.exists(twin) or not os.path.exists(mine):
        return None
    other = {round(r[0], 6): r for r in tum(twin)}
    d = [math.hypot(r[1] - o[1], r[2] - o[2]) for r in tum(mine) if r[0] >= min(starts)
         for o in [other.get(round(r[0], 6))] if o is not None]
    return max(d) if d else None


def fmt(x):
    return '-' if x is None else '%.2f' % x


def cells(err, ev, pulled):
    """The table's error cells of one estimate: position RMSE / max, heading RMSE / max, the
    largest error while a jump is on, and the jump's pull `pulled`."""
    jump = [e[1] for e in err for (a, b, k) in ev if k == 'jump' and a <= e[0] < b]
    return '%.2f / %.2f | %.2f / %.2f | %s | %s' % (
        math.sqrt(sum(e[1] ** 2 for e in err) / len(err)), max(e[1] for e in err),
        math.sqrt(sum(e[2] ** 2 for e in err) / len(err)), max(abs(e[2]) for e in err),
        '%.2f' % max(jump) if jump else '-', fmt(pulled))


def main():
    root, runs = sys.argv[1], sys.argv[2:]
    print('| run | position RMSE / max (m) | heading RMSE / max (deg) | max during jump (m) |'
          " jump's pull (m) | LiDAR accepted / rejected / re-acquired / degenerate |")
    print('|---|---|---|---|---|---|')
    for run in runs:
        data, est = os.path.join(root, run + '.data'), os.path.join(root, run + '.run')
        gt = tum(os.path.join(data, 'groundtruth.tum'))
        ev = events(os.path.join(data, 'events.csv'))
        err = errors(gt, tum(os.path.join(est, 'trajectory.tum')))
        s = json.load(open(os.path.join(est, 'summary.json')))['solver']['sensors'].get('lidar', {})
        fe = s.get('frontend', {})
        print('| %s | %s | %d / %d / %d / %d |' % (
            run, cells(err, ev, pull(root, run, '.run', ev)), s.get('accepted', 0),
            s.get('rejected_by_gate', 0), s.get('reacquired', 0), fe.get('degenerate_scans', 0)))
        batch = os.path.join(root, run + '.batch')
        if os.path.exists(os.path.join(batch, 'trajectory.tum')):
            be = errors(gt, tum(os.path.join(batch, 'trajectory.tum')))
            print('|   batch (skerry smooth), same data | %s | |' % cells(
                be, ev, pull(root, run, '.batch', ev)))
        base = os.path.join(root, run + '.baseline')
        if os.path.exists(os.path.join(base, 'trajectory.tum')):
            be = errors(gt, tum(os.path.join(base, 'trajectory.tum')))
            bs = json.load(open(os.path.join(base, 'baseline.json')))
            print('|   prior work (planar EKF + swarm), same data | %s |'
                  ' matches %d accepted / %d gated, %.1f s a match |' % (
                      cells(be, ev, pull(root, run, '.baseline', ev)), bs['accepted'], bs['gated'],
                      bs['seconds_per_match']))
        for (a, b, k) in ev:
            if k != 'outage' or b - a < 120:
                continue
            w = min(300.0, (b - a) / 2)
            first = [e[1] for e in err if a <= e[0] < a + w]
            last = [e[1] for e in err if b - w <= e[0] < b]
            inside = [e[1] for e in err if a <= e[0] < b]
            if first and last:
                print('|   GNSS outage %.0f-%.0f s | mean %.2f m, max %.2f m | first %.0f s mean %.2f m,'
                      ' last %.0f s mean %.2f m | | | |' % (
                          a, b, sum(inside) / len(inside), max(inside), w, sum(first) / len(first),
                          w, sum(last) / len(last)))


if __name__ == '__main__':
    main()

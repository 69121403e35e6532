#!/usr/bin/env python3
"""bench/lidar/mount_calibration.sh's helper (standard library only).
  --declare-off DATASET_YAML   rewrite the LiDAR's T_b_l as 2 degrees (about the body's z axis)
                               and (0.3, -0.2, 0) m off what the file says
  --table OUT SEEDS            the table of the runs in OUT: per IMU grade, declaration and
                               configuration, the medians over the seeds of the window's heading
                               and horizontal RMSE (the window's, and the batch's where
                               BATCH=1 made it), and for a calibrated mounting its yaw's error
                               (mean and sd over the seeds, and the window's own sigma) and its
                               horizontal lever arm's error"""
import bisect
import json
import math
import os
import re
import statistics
import sys

OFF_YAW_DEG = 2.0
OFF_LEVER_M = (0.3, -0.2, 0.0)
MOUNT = re.compile(r'(  lidar:\n(?:    .*\n)*?    T_b_l:\n      q_xyzw: \[)([^\]]*)(\]\n      p_m: \[)([^\]]*)(\])')


def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def yaw(q):
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def mount(path):
    m = MOUNT.search(open(path).read())
    if not m:
        sys.exit(f'{path}: no sensors.lidar.T_b_l')
    return [float(v) for v in m.group(2).split(',')], [float(v) for v in m.group(4).split(',')]


def declare_off(path):
    text = open(path).read()
    q, p = mount(path)
    h = math.radians(OFF_YAW_DEG) / 2
    q = qmul((0.0, 0.0, math.sin(h), math.cos(h)), q)
    p = [a + b for a, b in zip(p, OFF_LEVER_M)]
    text = MOUNT.sub(lambda m: m.group(1) + ', '.join(repr(v) for v in q) + m.group(3) +
                     ', '.join(repr(v) for v in p) + m.group(5), text, count=1)
    open(path, 'w').write(text)


def errors(run, truth):
    t_gt, rows = [], []
    with open(truth) as f:
        for line in f:
            if line.startswith('#') or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            t_gt.append(v[0])
            rows.append(v)
    dh, dp = [], []
    with open(run + '/states.csv') as f:
        head = f.readline().strip().split(',')
        ix = {k: i for i, k in enumerate(head)}
        for line in f:
            v = [float(x) for x in line.split(',')]
            j = min(bisect.bisect_left(t_gt, v[0]), len(t_gt) - 1)
            g = rows[j]
            e = yaw([v[ix[k]] for k in ('qx', 'qy', 'qz', 'qw')]) - yaw(g[4:8])
            dh.append(math.degrees(math.atan2(math.sin(e), math.cos(e))))
            dp.append(math.hypot(v[ix['px']] - g[1], v[ix['py']] - g[2]))
    rms = lambda a: math.sqrt(sum(x * x for x in a) / len(a))
    return rms(dh), rms(dp)


def table(out, seeds):
    print('| IMU | T_b_l declared | mounting | heading RMSE (median) | horizontal RMSE (median) '
          '| mounting yaw error: mean +- sd over seeds [each] | window sigma (median) '
          '| lever arm error, horizontal (median) |')
    print('|---|---|---|---|---|---|---|---|')
    for grade in ('consumer', 'tactical'):
        for declared in ('exact', 'off'):
            configs = ['held', 'calibrate']
            if os.path.isdir(f'{out}/{grade}-1.{declared}.calibrate.batch'):
                configs.append('calibrate, batch')
            for config in configs:
                heading, position, yaw_err, yaw_sd, lever = [], [], [], [], []
                for seed in range(1, seeds + 1):
                    d = f'{out}/{grade}-{seed}'
                    run = (f'{d}.{declared}.calibrate.batch' if config.endswith('batch') else
                           f'{d}.{declared}.{config}.run')
                    h, p = errors(run, f'{d}.exact.data/groundtruth.tum')
                    heading.append(h)
                    position.append(p)
                    q_true, p_true = mount(f'{d}.exact.data/dataset.yaml')
                    if config == 'held':
                        q_est, p_est = mount(f'{d}.{declared}.data/dataset.yaml')
                    else:
                        e = json.load(open(run + '/summary.json'))['extrinsics']['lidar']
                        q_est, p_est = e['q_xyzw'], e['p_m']
                        yaw_sd.append(e['sigma_rotation_deg'][2])
                    q_inv = (-q_true[0], -q_true[1], -q_true[2], q_true[3])
                    yaw_err.append(math.degrees(yaw(qmul(q_est, q_inv))))
                    lever.append(math.hypot(p_est[0] - p_true[0], p_est[1] - p_true[1]))
                spread = statistics.stdev(yaw_err) if len(yaw_err) > 1 else 0.0
                each = ' '.join(f'{x:+.2f}' for x in yaw_err)
                sigma = f'{statistics.median(yaw_sd):.2f} deg' if yaw_sd else '(held)'
                print(f'| {grade} | {declared} | {config} | {statistics.median(heading):.2f} deg '
                      f'| {statistics.median(position):.2f} m '
                      f'| {statistics.mean(yaw_err):+.2f} +- {spread:.2f} deg [{each}] | {sigma} '
                      f'| {statistics.median(lever):.2f} m |')


if __name__ == '__main__':
    if len(sys.argv) == 3 and sys.argv[1] == '--declare-off':
        declare_off(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == '--table':
        table(sys.argv[2], int(sys.argv[3]))
    else:
        sys.exit(__doc__)

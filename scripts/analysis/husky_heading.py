#!/usr/bin/env python3
"""Husky (no ground truth): how far a skerry run is from the raw fixes, how its heading compares
with the course over ground on straight stretches, and how much of the accelerometer's signal is
motion. The figures of docs/results.md, "Real GNSS + IMU: Husky". Standard library only.

usage: husky_heading.py RUN_DIR DATASET_DIR RAW_HUSKY_DIR
  RUN_DIR      `skerry run --out` folder (states.csv)
  DATASET_DIR  `skerry import --format husky --out` folder (gnss.csv, imu.csv)
  RAW_HUSKY_DIR ../shared/data/husky (husky_velocity_controller_odom.csv)
"""
import bisect
import csv
import math
import sys


def num(x):
    try:
        return float(x)
    except ValueError:
        return x  # frame names in the raw CSVs


def rows(path):
    with open(path) as f:
        r = list(csv.reader(f))
    return [[num(x) for x in row] for row in r[1:]]


def qrot(q, v):  # q = (x, y, z, w) rotating v
    x, y, z, w = q
    t = (2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0]))
    return (v[0] + w * t[0] + y * t[2] - z * t[1], v[1] + w * t[1] + z * t[0] - x * t[2],
            v[2] + w * t[2] + x * t[1] - y * t[0])


def heading_deg(q):  # body x axis, clockwise from north (world ENU)
    x = qrot(q, (1.0, 0.0, 0.0))
    return math.degrees(math.atan2(x[0], x[1]))


def wrap(a):
    return (a + 180.0) % 360.0 - 180.0


def rms(a):
    return math.sqrt(sum(x * x for x in a) / len(a))


def pct(a, p):
    s = sorted(a)
    return s[min(len(s) - 1, int(p * len(s)))]


def main(run, data, raw):
    st = rows(run + '/states.csv')
    ts = [s[0] for s in st]

    def state_at(t):
        return st[min(bisect.bisect_left(ts, t), len(ts) - 1)]

    g = rows(data + '/gnss.csv')
    lat0, lon0, R = g[0][1], g[0][2], 6378137.0
    # Local east/north of the fixes (equirectangular about the first: millimetres over 200 m).
    F = [(r[0], math.radians(r[2] - lon0) * R * math.cos(math.radians(lat0)),
          math.radians(r[1] - lat0) * R) for r in g]
    Ft = [f[0] for f in F]

    d = [math.hypot(state_at(t)[1] - e, state_at(t)[2] - n) for t, e, n in F
         if abs(state_at(t)[0] - t) < 0.06]
    print(f"estimate - fix: {len(d)} fixes, RMS {rms(d):.2f} m, median {pct(d, 0.5):.2f} m, "
          f"max {max(d):.2f} m")
    sd = [math.hypot(F[k + 1][1] - 2 * F[k][1] + F[k - 1][1], F[k + 1][2] - 2 * F[k][2] + F[k - 1][2])
          for k in range(1, len(F) - 1)]
    print(f"fix second differences RMS {rms(sd):.3f} m: white noise of "
          f"{rms(sd) / math.sqrt(6):.3f} m per axis pair if the track is smooth")

    # Straight stretches: 4 s of fixes at > 0.5 m/s whose two halves' courses agree within 5 deg.
    err, z2, sig = [], [], []
    for k in range(len(F)):
        j = bisect.bisect_left(Ft, F[k][0] + 4.0)
        m = bisect.bisect_left(Ft, F[k][0] + 2.0)
        if j >= len(F):
            break
        c1 = math.degrees(math.atan2(F[m][1] - F[k][1], F[m][2] - F[k][2]))
        c2 = math.degrees(math.atan2(F[j][1] - F[m][1], F[j][2] - F[m][2]))
        de, dn = F[j][1] - F[k][1], F[j][2] - F[k][2]
        if math.hypot(de, dn) / (F[j][0] - F[k][0]) < 0.5 or abs(wrap(c1 - c2)) > 5.0:
            continue
        s = state_at(0.5 * (F[k][0] + F[j][0]))
        e = wrap(heading_deg(s[4:8]) - math.degrees(math.atan2(de, dn)))
        err.append(e)
        sig.append(s[20])
        z2.append((e / s[20]) ** 2)
    print(f"heading - course over ground, {len(err)} straight stretches: mean {sum(err)/len(err):.1f} "
          f"deg, RMS {rms(err):.1f} deg, 5-95 % {pct(err, 0.05):.1f}..{pct(err, 0.95):.1f} deg; "
          f"claimed sigma median {pct(sig, 0.5):.1f} deg; mean (error/sigma)^2 "
          f"{sum(z2)/len(z2):.2f} (1 if consistent)")

    # Accelerometer in body axes (T_b_i of the import: imu x -> -y, y -> z, z -> -x) against
    # motion from the wheel odometry (forward speed, 10 Hz): 1 s means.
    imu = rows(data + '/imu.csv')
    t0 = imu[0][0]
    bins = {}
    for r in imu:
        b = bins.setdefault(int(r[0] - t0), [0, 0.0, 0.0, 0.0])
        b[0] += 1
        b[1] += r[2]   # yaw rate about body z = imu y
        b[2] += -r[6]  # body x = -imu z
        b[3] += -r[4]  # body y = -imu x
    od = rows(raw + '/husky_velocity_controller_odom.csv')
    Ot = [r[1] for r in od]

    def odv(t):
        return od[min(bisect.bisect_left(Ot, t), len(od) - 1)][11]

    lat_x, lat_y, lon_x, lon_y = [], [], [], []
    for k in sorted(bins):
        if k + 1 not in bins or k - 1 not in bins:
            continue
        n, wz, fx, fy = bins[k]
        t = t0 + k + 0.25  # odometry lags the IMU by about a quarter second
        v = sum(odv(t + 0.1 * i) for i in range(10)) / 10
        lat_x.append(v * wz / n)
        lat_y.append(fy / n)
        lon_x.append(odv(t + 1.0) - odv(t))
        lon_y.append(fx / n)
    for name, X, Y in (("lateral (v * yaw rate)", lat_x, lat_y), ("longitudinal (dv/dt)", lon_x, lon_y)):
        mx, my = sum(X) / len(X), sum(Y) / len(Y)
        sxx = sum((x - mx) ** 2 for x in X)
        syy = sum((y - my) ** 2 for y in Y)
        sxy = sum((x - mx) * (y - my) for x, y in zip(X, Y))
        print(f"accelerometer vs odometry, {name}: slope {sxy/sxx:.2f}, correlation "
              f"{sxy/math.sqrt(sxx*syy):.2f}; motion {math.sqrt(sxx/len(X)):.3f} m/s^2 RMS, "
              f"accelerometer {math.sqrt(syy/len(Y)):.3f} m/s^2 RMS (1 s means)")


if __name__ == '__main__':
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])

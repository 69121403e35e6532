#!/usr/bin/env python3
"""One Markdown table of a scenario's results folder written by run_peers.sh.

  peer_table.py RESULTS_DIR MODE...

Times: skerry's from its own outputs (`skerry run`: the sum of updates.csv's update_ms, the
wall time of every window update; `skerry smooth`: summary.json timing.window_s +
timing.batch_solve_s, its covariance pass shown apart), GTSAM's from gtsam_peer's JSON (the sum of
its per-keyframe update times; batch-lm: that causal pass + the LM solve). Accuracy: `skerry
evaluate`'s JSON of each trajectory against the same ground truth and events.csv.
"""
import csv
import json
import math
import os
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    return f"{x:.{digits}f}"


def accuracy(ev):
    """horizontal RMSE and max outside outages, heading RMSE, error at the first outage's end."""
    if not ev:
        return [None] * 4
    e = ev.get("events", {})
    h = e.get("horizontal_outside_outages_m") or ev.get("horizontal_m", {})
    outages = e.get("outages") or [{}]
    return [h.get("rmse"), h.get("max"), ev.get("heading_deg", {}).get("rmse"),
            outages[0].get("horizontal_error_at_end_m")]


def percentile(values, p):
    v = sorted(values)
    if not v:
        return None
    pos = p * (len(v) - 1)
    lo = int(math.floor(pos))
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (pos - lo) * (v[hi] - v[lo])


def main():
    out, modes = sys.argv[1], sys.argv[2:]
    rows = []
    # skerry's window: every update's wall time is in updates.csv.
    run_time = None
    upd = os.path.join(out, "skerry-run", "updates.csv")
    if os.path.exists(upd):
        with open(upd) as f:
            ms = [float(r["update_ms"]) for r in csv.DictReader(f)]
        run_time = sum(ms) / 1e3
        rows.append(["skerry run (window)", run_time, percentile(ms, 0.5), percentile(ms, 0.95),
                     max(ms), None] + accuracy(load(os.path.join(out, "skerry-run.eval.json"))))
    smooth_time = None
    sm = load(os.path.join(out, "skerry-smooth", "summary.json"))
    if sm:
        t = sm["timing"]
        smooth_time = t["window_s"] + t["batch_solve_s"]
        u = sm["solver"].get("initial_window", {}).get("update_ms", {})
        rows.append([f"skerry smooth (window {t['window_s']:.2f} s + batch "
                     f"{t['batch_solve_s']:.2f} s, {sm['solver'].get('iterations')} it; "
                     f"+{t.get('covariance_s', 0):.2f} s covariances not counted)",
                     smooth_time, u.get("median"), u.get("p95"), u.get("max"), None]
                    + accuracy(load(os.path.join(out, "skerry-smooth.eval.json"))))
    for mode in modes:
        j = load(os.path.join(out, f"gtsam-{mode}.json"))
        if not j:
            rows.append([f"GTSAM {mode}: failed"] + [None] * 9)
            continue
        ref = smooth_time if mode == "batch-lm" else run_time
        label = f"GTSAM {mode}"
        if mode == "batch-lm":
            label += (f" (pass {j['init_pass_s']:.2f} s + LM {j['lm_s']:.2f} s, "
                      f"{j['lm_iterations']} it)")
        label += (f" [fixes {j['fixes_accepted']}+{j['fixes_reacquired']} re-acq / "
                  f"{j['fixes_rejected']} rejected, {j['threads']} thread(s), "
                  f"{j['peak_rss_mb']:.0f} MB]")
        rows.append([label, j["estimator_s"], j["update_median_ms"], j["update_p95_ms"],
                     j["update_max_ms"], j["estimator_s"] / ref if ref else None]
                    + accuracy(load(os.path.join(out, f"gtsam-{mode}.eval.json"))))

    print("| estimator | time s | update median ms | p95 ms | max ms | time / skerry's | "
          "horiz. RMSE outside outages m | horiz. max outside outages m | heading RMSE deg | "
          "error at outage end m |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join([r[0], fmt(r[1], 2), fmt(r[2]), fmt(r[3]), fmt(r[4], 2),
                                 fmt(r[5], 2), fmt(r[6]), fmt(r[7]), fmt(r[8]), fmt(r[9], 2)])
              + " |")
    print()
    print("GTSAM ratios: isam2 and batch-fixed-lag against `skerry run`, batch-lm against "
          "`skerry smooth` (window + batch solve). skerry smooth's update columns are its "
          "first (window) pass; batch-lm's are its causal iSAM2 pass.")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""One Markdown table of a scenario's results folder written by run_peers.sh.

  peer_table.py RESULTS_DIR RUN...

RUN is a client run as run_peers.sh names it: MODE (the client's default update policy, every
fix) or MODE:keyframe / MODE:fix; its files are gtsam-MODE[-POLICY].{json,eval.json,log}, and
gtsam-....skipped when run_peers.sh was told to skip it.

With run_peers.sh --repeats N the times are the medians over the N interleaved repeats
(RESULTS_DIR and RESULTS_DIR/repeat-K) and each ratio the median of the repeats' own ratios.
Times: skerry's from its own outputs (`skerry run`: the sum of updates.csv's update_ms, the
wall time of every window update, its solves alone in the "updates s" column; `skerry smooth`:
summary.json timing.window_s + timing.batch_solve_s, its covariance pass shown apart), GTSAM's
from gtsam_peer's JSON (estimator_s, the sum of its per-keyframe times; batch-lm: that causal
pass + the LM solve), with the smoother's update() calls (update_s) and the gate's covariance
queries (gate_s) apart. Accuracy: `skerry evaluate`'s JSON of each trajectory against the same
ground truth and events.csv.
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


def run_file(run):
    """'isam2:keyframe' -> 'gtsam-isam2-keyframe' (the stem run_peers.sh writes)."""
    return "gtsam-" + run.replace(":", "-")


def last_line(path):
    try:
        with open(path) as f:
            lines = [line.strip() for line in f if line.strip()]
        return lines[-1] if lines else ""
    except OSError:
        return ""


def median(values):
    v = [x for x in values if x is not None]
    return percentile(v, 0.5) if v else None


def repeat_dirs(out):
    """The results folder of repeat 1 and those of the repeats after it (run_peers.sh
    --repeats), in order."""
    more = []
    for name in os.listdir(out):
        if name.startswith("repeat-") and name[7:].isdigit():
            more.append((int(name[7:]), os.path.join(out, name)))
    return [out] + [d for _, d in sorted(more)]


def window_times(d, name="skerry-run"):
    """`skerry run` in folder d/name: (estimator s, solves s, update times ms) or None."""
    upd = os.path.join(d, name, "updates.csv")
    if not os.path.exists(upd):
        return None
    with open(upd) as f:
        records = list(csv.DictReader(f))
    ms = [float(r["update_ms"]) for r in records]
    return sum(ms) / 1e3, sum(float(r["solve_ms"]) for r in records) / 1e3, ms


def smooth_timing(d, name="skerry-smooth"):
    sm = load(os.path.join(d, name, "summary.json"))
    return sm if sm and "timing" in sm else None


def smooth_seconds(s):
    return s["timing"]["window_s"] + s["timing"]["batch_solve_s"] if s else None


def skerry_rows(out, dirs, run_t, smooth, label):
    """The table's rows of skerry's window and batch (run_t, smooth: per repeat)."""
    rows = []
    if run_t[0]:
        ms = run_t[0][2]
        rows.append([f"skerry run (window{label})", median([t[0] for t in run_t if t]),
                     median([t[1] for t in run_t if t]), None, percentile(ms, 0.5),
                     percentile(ms, 0.95), max(ms), None, None]
                    + accuracy(load(os.path.join(out, "skerry-run" + label_stem(label)
                                                 + ".eval.json"))))
    if smooth[0]:
        sm = smooth[0]
        window_s = median([s["timing"]["window_s"] for s in smooth if s])
        batch_s = median([s["timing"]["batch_solve_s"] for s in smooth if s])
        cov_s = median([s["timing"].get("covariance_s", 0) for s in smooth if s])
        u = sm["solver"].get("initial_window", {}).get("update_ms", {})
        rows.append([f"skerry smooth{label} (window {window_s:.2f} s + batch "
                     f"{batch_s:.2f} s, {sm['solver'].get('iterations')} it; "
                     f"+{cov_s:.2f} s covariances not counted)",
                     median([smooth_seconds(s) for s in smooth]), None, None, u.get("median"),
                     u.get("p95"), u.get("max"), None, None]
                    + accuracy(load(os.path.join(out, "skerry-smooth" + label_stem(label)
                                                 + ".eval.json"))))
    return rows


def label_stem(label):
    return "-default" if label else ""


def main():
    out, runs = sys.argv[1], sys.argv[2:]
    dirs = repeat_dirs(out)
    # Per repeat: skerry's window and batch times, the reference of each ratio in that repeat.
    run_t = [window_times(d) for d in dirs]
    smooth = [smooth_timing(d) for d in dirs]
    smooth_t = [smooth_seconds(s) for s in smooth]
    # The same with skerry's default preset (its gyro calibration on), when run_peers.sh ran it.
    default_label = ", default preset: + the gyro's calibration"
    run_d = [window_times(d, "skerry-run-default") for d in dirs]
    smooth_d = [smooth_timing(d, "skerry-smooth-default") for d in dirs]
    # Each row: label, time s, updates s, gate s, keyframe median/p95/max ms, ratio,
    # ratio without the gate, then the four accuracy figures. Times are medians over the
    # repeats, ratios the medians of each repeat's ratio.
    rows = skerry_rows(out, dirs, run_t, smooth, "")
    rows += skerry_rows(out, dirs, run_d, smooth_d, default_label)
    against_default = []  # GTSAM's runs against skerry's default preset
    for run in runs:
        stem = os.path.join(out, run_file(run))
        mode = run.split(":")[0]
        if os.path.exists(stem + ".skipped"):
            rows.append([f"GTSAM {run}: not run (skipped: {last_line(stem + '.skipped')})"]
                        + [None] * 12)
            continue
        js = [load(os.path.join(d, run_file(run)) + ".json") for d in dirs]
        j = js[0]
        if not j:
            rows.append([f"GTSAM {run}: failed ({last_line(stem + '.log')[:120]})"]
                        + [None] * 12)
            continue
        refs = smooth_t if mode == "batch-lm" else [t[0] if t else None for t in run_t]
        ratios = [x["estimator_s"] / r if x and r else None for x, r in zip(js, refs)]
        ratios_ng = [(x["estimator_s"] - x["gate_s"]) / r if x and r else None
                     for x, r in zip(js, refs)]
        refs_d = ([smooth_seconds(s) for s in smooth_d] if mode == "batch-lm"
                  else [t[0] if t else None for t in run_d])
        if any(refs_d):
            ratio_d = median([x["estimator_s"] / r if x and r else None
                              for x, r in zip(js, refs_d)])
            ratio_d_ng = median([(x["estimator_s"] - x["gate_s"]) / r if x and r else None
                                 for x, r in zip(js, refs_d)])
            against_default.append(f"{run} / skerry {'smooth' if mode == 'batch-lm' else 'run'}"
                                   f" {fmt(ratio_d, 2)} (without its gate {fmt(ratio_d_ng, 2)})")
        policy = "every fix" if j.get("update_on") == "fix" else "every keyframe"
        label = f"GTSAM {mode}, {policy}"
        if mode != "batch-fixed-lag":
            label += f", {j.get('factorization')}"
        if mode == "batch-lm":
            label += (f" (pass {median([x['init_pass_s'] for x in js if x]):.2f} s + LM "
                      f"{median([x['lm_s'] for x in js if x]):.2f} s, "
                      f"{j['lm_iterations']} it)")
        label += (f" [fixes {j['fixes_accepted']}+{j['fixes_reacquired']} re-acq / "
                  f"{j['fixes_rejected']} rejected, {j['smoother_updates']} updates, "
                  f"{j['threads']} thread(s), {j['peak_rss_mb']:.0f} MB]")
        rows.append([label, median([x["estimator_s"] for x in js if x]),
                     median([x["update_s"] for x in js if x]),
                     median([x["gate_s"] for x in js if x]), j["keyframe_median_ms"],
                     j["keyframe_p95_ms"], j["keyframe_max_ms"], median(ratios),
                     median(ratios_ng)]
                    + accuracy(load(stem + ".eval.json")))

    print("| estimator | time s | updates s | gate s | keyframe median ms | p95 ms | max ms | "
          "time / skerry's | without gate / skerry's | horiz. RMSE outside outages m | "
          "horiz. max outside outages m | heading RMSE deg | error at outage end m |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        cells = [r[0], fmt(r[1], 2), fmt(r[2], 2), fmt(r[3], 2), fmt(r[4]), fmt(r[5]),
                 fmt(r[6], 2), fmt(r[7], 2), fmt(r[8], 2), fmt(r[9]), fmt(r[10]), fmt(r[11]),
                 fmt(r[12], 2)]
        print("| " + " | ".join(cells) + " |")
    print()
    print("time: the estimator's whole work per keyframe, summed; updates: the smoother's "
          "update() calls (skerry run: its solves); gate: GTSAM's covariance queries for the "
          "chi-square gate (inside skerry's time). Ratios: isam2 and batch-fixed-lag against "
          "`skerry run`, batch-lm against `skerry smooth` (window + batch solve). skerry "
          "smooth's keyframe columns are its first (window) pass; batch-lm's its causal pass. "
          f"Over {len(dirs)} interleaved repeat(s): times are medians, ratios the median of "
          "each repeat's ratio; keyframe columns and accuracy from the first (every run is "
          "deterministic).")
    if against_default:
        print()
        print("Against skerry's default preset (it also estimates the gyro's calibration, which "
              "the client does not; ratios as above): " + "; ".join(against_default) + ".")


if __name__ == "__main__":
    main()

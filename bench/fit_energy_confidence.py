#!/usr/bin/env python3
"""Joint-angle errors by the body fit's energy: the evidence for fit.trusted_energy and for the
confidence of untrusted and lost fits (docs/fitting.md, "A fit's energy").

    bench/fit_energy_confidence.py [--trusted-energy E] [--smoothing-frames N] DIR [DIR ...]

DIR: a bench/joint_angles.sh KEEP directory (each session's NAME.out results with
fit_energy.csv and NAME.gt truth). Run the sessions with FIT_OPTIONS='fit.trusted_energy=100' so
that no frame below fit.lost_energy has its confidences capped: the confident values (confidence
>= 0.5) are then those the camera's tracking and the angles' own limits make confident, whatever
the energy.

First table: per band of the frame's energy E, the frames and, per angle read from the fitted
joints (left and right pooled; pronation is the IMU's and left out), the confident values more
than 15 deg off the truth over the confident values. A confident value promises a 99 % bound of
15 deg, so a band whose every angle keeps to 1 % is one the fit can be trusted in.

Second table: the 99th percentile of the absolute error (and RMS) pooled over those angles, and
the confidence that bound gives (2^-(bound / 15 deg)^2, forearm::confidence_from_bound99_rad),
for the confident values of frames at or below the trusted energy, between it and the lost
energy, and for every value of the frames above the lost energy (whose confidences the lost fit
has already set to 0).

Third table: every angle's confident values (pronation too) and those more than 15 deg off, with
the trusted energy applied as the server applies it, to every fit of the frame's smoothing window
(the frame and --smoothing-frames / 2 neighbours each side in fit order, the window shrinking at
the session's ends as fit::PoseSmoother's), beside the frame's own fit alone: a value stays
confident where its run gave it confidence >= 0.5 and the rule trusts its frame. Its last row
counts the values as the results emit them (confidence >= 0.5, no rule applied here): on a run
with the default fit.trusted_energy, what a user gets.
"""
import collections
import csv
import glob
import math
import os
import sys

ANGLES = ["thorax_flexion", "thorax_lateral_tilt", "thorax_axial_rotation", "elevation", "plane_of_elevation",
          "humerus_axial_rotation", "elbow_flexion"]
EDGES = [0, 10, 15, 20, 25, 30, 40, 50, 60, 80, 100]
TRUSTED_ENERGY = 10.0  # fit.trusted_energy's default; --trusted-energy E splits the second table at E
LOST_ENERGY = 100.0  # fit.lost_energy's default


def columns(angle):
    return [angle] if angle.startswith("thorax") else [f"left_{angle}", f"right_{angle}"]


def band_of(energy):
    if math.isnan(energy):
        return len(EDGES) - 1
    return max(i for i, edge in enumerate(EDGES) if energy >= edge)


def band_name(b):
    return f"{EDGES[b]}-{EDGES[b + 1]}" if b + 1 < len(EDGES) else f">= {EDGES[b]} (lost) or NaN"


def percentile_99(sorted_errors):
    return sorted_errors[int(0.99 * (len(sorted_errors) - 1))]


SMOOTHING_FRAMES = 3  # fit.smoothing_frames' default; --smoothing-frames N


def window_energies(energies):
    """The largest energy of each frame's smoothing window (NaN if any is NaN), in fit order."""
    half = SMOOTHING_FRAMES // 2
    out = []
    for i in range(len(energies)):
        reach = min(half, i, len(energies) - 1 - i)
        window = energies[i - reach:i + reach + 1]
        out.append(float("nan") if any(math.isnan(e) for e in window) else max(window))
    return out


def angle_error(row, true_row, column):
    """|result - truth| of one angle column in degrees, wrapped to 0..180; None where either is empty."""
    if row[column] == "" or true_row[column] == "":
        return None
    error = abs(float(row[column]) - float(true_row[column])) % 360
    return min(error, 360 - error)


def main(works):
    by_rule = {"own": [0, 0], "window": [0, 0], "emitted": [0, 0]}  # confident values, beyond 15 deg
    frames = collections.Counter()
    confident = collections.defaultdict(lambda: collections.defaultdict(list))  # angle -> band -> |error|
    lost_errors = []
    sessions = 0
    for work in works:
        for out in sorted(glob.glob(os.path.join(work, "*.out"))):
            energy_file = os.path.join(out, "fit_energy.csv")
            if not os.path.exists(energy_file):
                continue
            sessions += 1
            energy_rows = [(int(r["t_us"]), float(r["fit_energy"])) for r in csv.DictReader(open(energy_file))]
            energy = dict(energy_rows)
            window = dict(zip((t for t, _ in energy_rows), window_energies([e for _, e in energy_rows])))
            truth = {r["t_s"]: r for r in csv.DictReader(open(out[: -len(".out")] + ".gt/joint_angles.csv"))}
            for row in csv.DictReader(open(os.path.join(out, "joint_angles.csv"))):
                true_row = truth.get(row["t_s"])
                t_us = round(float(row["t_s"]) * 1e6)
                e = energy.get(t_us)
                if true_row is None or e is None:
                    continue
                b = band_of(e)
                frames[b] += 1
                trusted = {"own": e <= TRUSTED_ENERGY, "window": window[t_us] <= TRUSTED_ENERGY, "emitted": True}
                for column in [c for angle in ANGLES + ["pronation"] for c in columns(angle)]:
                    error = angle_error(row, true_row, column)
                    if error is None or float(row[column + "_confidence"]) < 0.5:
                        continue
                    for rule, counts in by_rule.items():
                        if trusted[rule]:
                            counts[0] += 1
                            counts[1] += error > 15
                for angle in ANGLES:
                    for column in columns(angle):
                        error = angle_error(row, true_row, column)
                        if error is None:
                            continue
                        if b == len(EDGES) - 1:
                            lost_errors.append(error)
                        elif float(row[column + "_confidence"]) >= 0.5:
                            confident[angle][b].append(error)
    print(f"{sessions} sessions")
    print()
    print("| energy E | frames | " + " | ".join(a.replace("_", " ") for a in ANGLES) + " |")
    print("|---|---:|" + "---:|" * len(ANGLES))
    for b in sorted(frames):
        if b == len(EDGES) - 1:
            continue
        cells = []
        for angle in ANGLES:
            errors = confident[angle][b]
            beyond = sum(x > 15 for x in errors)
            cells.append(f"{beyond} / {len(errors)}" + (f" ({100 * beyond / len(errors):.1f} %)" if errors else ""))
        print(f"| {band_name(b)} | {frames[b]} | " + " | ".join(cells) + " |")
    print(f"| {band_name(len(EDGES) - 1)} | {frames[len(EDGES) - 1]} | (confidence 0) |" + " |" * (len(ANGLES) - 1))
    print()
    print("| frames | values | RMS, deg | 99 % bound, deg | confidence the bound gives |")
    print("|---|---:|---:|---:|---:|")
    groups = [
        (f"E <= {TRUSTED_ENERGY:g}, confident values", lambda b: EDGES[b] < TRUSTED_ENERGY),
        (f"{TRUSTED_ENERGY:g} < E <= {LOST_ENERGY:g}, confident values",
         lambda b: TRUSTED_ENERGY <= EDGES[b] < LOST_ENERGY),
    ]
    for name, in_group in groups:
        errors = sorted(x for angle in ANGLES for b, v in confident[angle].items() if in_group(b) for x in v)
        report(name, errors)
    report(f"E > {LOST_ENERGY:g} (lost), every value", sorted(lost_errors))
    print()
    print(f"| trusted where (E <= {TRUSTED_ENERGY:g}) | confident values | beyond 15 deg |")
    print("|---|---:|---:|")
    for rule, name in (("own", "the frame's own fit"), ("window", "every fit of its smoothing window"),
                       ("emitted", "as the results emit them")):
        n, beyond = by_rule[rule]
        print(f"| {name} | {n} | {beyond} ({100 * beyond / max(n, 1):.2f} %) |")


def report(name, errors):
    if not errors:
        print(f"| {name} | 0 | | | |")
        return
    bound = percentile_99(errors)
    rms = math.sqrt(sum(x * x for x in errors) / len(errors))
    print(f"| {name} | {len(errors)} | {rms:.1f} | {bound:.1f} | {2 ** (-(bound / 15) ** 2):.3g} |")


if __name__ == "__main__":
    args = sys.argv[1:]
    while len(args) >= 2 and args[0] in ("--trusted-energy", "--smoothing-frames"):
        if args[0] == "--trusted-energy":
            TRUSTED_ENERGY = float(args[1])
        else:
            SMOOTHING_FRAMES = int(args[1])
        args = args[2:]
    if not args:
        sys.exit(__doc__)
    main(args)

#!/usr/bin/env python3
"""Joint-angle errors by the camera's tracking of the joints they are read from.

    bench/untracked_joint_angles.py DIR

DIR: a bench/joint_angles.sh KEEP directory (each session's NAME.out results and NAME.gt truth).
For every angle value whose joints include exactly one joint the camera did not track, the error
against the truth is pooled under that joint (left and right together); "none" pools the same
angles where every joint is tracked. Prints RMS, the 99th percentile and the confidence that
bound gives (2^-(bound / 15 deg)^2, forearm::confidence_from_bound99_rad): the evidence for the
fit's confidence of an untracked joint (docs/fitting.md, "Joint confidence").

A second table gives the girdle elevation's own error where every joint it is read from is
tracked (the collars have no camera joint and count as tracked): RMS, 99th percentile, the share
beyond 15 deg and beyond the default 99 % bound (2.576 x measures.girdle_elevation_uncertainty_deg,
8.4 deg): the evidence for that option (docs/measures.md, "Confidence").

A joint is untracked where its fitted confidence is below 1; frames whose fit was lost or ended
above fit.trusted_energy (the pelvis, which the camera's SpineBase backs, below 0.5) are left
out. Girdle elevation is left out (its error is the girdle's own, tracked or not), as are elbow
flexions whose confidence lies between 0 and 0.5 (limited by the arm lengths, docs/measures.md,
not by a joint) and planes of elevation held in the gimbal lock.
"""
import collections
import csv
import glob
import math
import os
import sys

THORAX = ["spine2", "neck", "left_collar", "right_collar"]
ARM_ANGLES = ["elevation", "plane_of_elevation", "elbow_flexion", "humerus_axial_rotation"]


def joints_of(angle):
    if angle.startswith("thorax"):
        return THORAX
    side, kind = angle.split("_", 1)
    shoulder, elbow, wrist = (f"{side}_{j}" for j in ("shoulder", "elbow", "wrist"))
    if kind == "elbow_flexion":
        return [shoulder, elbow, wrist]
    if kind == "humerus_axial_rotation":
        return THORAX + [shoulder, elbow, wrist]
    return THORAX + [shoulder, elbow]


GIRDLE_RMS_DEG = 8.4  # measures.girdle_elevation_uncertainty_deg's default


def percentile_99(sorted_errors):
    return sorted_errors[int(0.99 * (len(sorted_errors) - 1))]


def main(work):
    angles = ["thorax_flexion", "thorax_lateral_tilt", "thorax_axial_rotation"] + [
        f"{side}_{kind}" for side in ("left", "right") for kind in ARM_ANGLES]
    errors = collections.defaultdict(list)
    sessions = collections.defaultdict(set)
    girdle_errors, girdle_sessions = [], set()
    for out in sorted(glob.glob(os.path.join(work, "*.out"))):
        name = os.path.basename(out)[: -len(".out")]
        confidence = collections.defaultdict(dict)
        for row in csv.DictReader(open(os.path.join(out, "smpl_joints.csv"))):
            confidence[int(row["t_us"])][row["joint_name"]] = float(row["confidence"])
        truth = {r["t_s"]: r for r in csv.DictReader(open(os.path.join(work, name + ".gt", "joint_angles.csv")))}
        for row in csv.DictReader(open(os.path.join(out, "joint_angles.csv"))):
            true_row = truth.get(row["t_s"])
            joints = confidence.get(round(float(row["t_s"]) * 1e6))
            if not true_row or not joints or joints.get("pelvis", 1.0) < 0.5:
                continue
            for side in ("left", "right"):
                angle = f"{side}_girdle_elevation"
                if row[angle] == "" or true_row[angle] == "":
                    continue
                if all(joints.get(j, 1.0) == 1.0 for j in THORAX + [f"{side}_shoulder"]):
                    girdle_errors.append(abs(float(row[angle]) - float(true_row[angle])))
                    girdle_sessions.add(name)
            for angle in angles:
                if row[angle] == "" or true_row[angle] == "":
                    continue
                c = float(row[angle + "_confidence"])
                if (angle.endswith("elbow_flexion") and 0 < c < 0.5) or (angle.endswith("plane_of_elevation") and c == 0):
                    continue
                untracked = [j for j in joints_of(angle) if joints.get(j, 1.0) < 1.0]
                if len(untracked) > 1:
                    continue
                key = untracked[0].replace("left_", "").replace("right_", "") if untracked else "none"
                error = abs(float(row[angle]) - float(true_row[angle]))
                errors[key].append(min(error, 360 - error))
                sessions[key].add(name)
    print("| untracked joint | angle values | sessions | RMS, deg | 99 % bound, deg | confidence the bound gives |")
    print("|---|---:|---:|---:|---:|---:|")
    for key in sorted(errors, key=lambda k: (k == "none", k)):
        e = sorted(errors[key])
        bound = percentile_99(e)
        rms = math.sqrt(sum(x * x for x in e) / len(e))
        print(f"| {key} | {len(e)} | {len(sessions[key])} | {rms:.1f} | {bound:.1f} | {2 ** (-(bound / 15) ** 2):.3f} |")
    if girdle_errors:
        e = sorted(girdle_errors)
        rms = math.sqrt(sum(x * x for x in e) / len(e))
        default_bound = 2.576 * GIRDLE_RMS_DEG
        share = lambda limit: 100.0 * sum(x > limit for x in e) / len(e)
        print()
        print("| girdle elevation, joints tracked | values | sessions | RMS, deg | 99 % bound, deg | beyond 15 deg "
              f"| beyond {default_bound:.1f} deg (default bound) |")
        print("|---|---:|---:|---:|---:|---:|---:|")
        print(f"| both sides | {len(e)} | {len(girdle_sessions)} | {rms:.1f} | {percentile_99(e):.1f} "
              f"| {share(15):.1f} % | {share(default_bound):.2f} % |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])

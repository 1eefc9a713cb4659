#!/usr/bin/env python3
"""Choose the real-data model misfit on some scenes and check it on the others.

The misfit enters every covariance as an isotropic term (estimator::model_misfit_covariance):
    S(t, r) = S0 + (t^2 + 2/3 (r * radius)^2) I,   radius = half the model's diameter,
so one `estimate` run with no misfit gives the NEES of every candidate. Run

    build/clutterscope estimate DATASET --out RUN --model-misfit-mm 0 --model-misfit-deg 0 --no-time
    scripts/choose_real_misfit.py RUN/estimates.csv DATASET/models/models_info.json \
        --choice-scenes 0,3

It picks the smallest translation sigma (mm, a grid of --step) whose 95% ellipsoids cover at
least --target of the errors on the choice scenes (rotation fixed at --rotation-deg), and
prints the coverage (share of NEES <= 7.8147, the chi-square 3-dof 95% quantile) on the choice
scenes and on the check scenes (all others), with the paper's confident decision (every axis
variance <= 0.25 cm^2 and consistent) and the confident objects' mean error.
Standard library only.
"""

import argparse
import csv
import json
import math
import sys

CHI2_3_95 = 7.8147


def inverse3(m):
    a, b, c = m[0]
    d, e, f = m[1]
    g, h, i = m[2]
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    if not det > 0:
        return None
    return [[(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det],
            [(f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det],
            [(d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det]]


def nees(row, add_cm2):
    s = [[row["var_x_cm2"] + add_cm2, row["cov_xy_cm2"], row["cov_xz_cm2"]],
         [row["cov_xy_cm2"], row["var_y_cm2"] + add_cm2, row["cov_yz_cm2"]],
         [row["cov_xz_cm2"], row["cov_yz_cm2"], row["var_z_cm2"] + add_cm2]]
    inv = inverse3(s)
    if inv is None:
        return None
    e = [row["err_x_cm"], row["err_y_cm"], row["err_z_cm"]]
    return sum(e[r] * inv[r][c] * e[c] for r in range(3) for c in range(3))


def misfit_cm2(translation_mm, rotation_deg, radius_mm):
    rotation_mm = math.radians(rotation_deg) * radius_mm
    return 1e-2 * (translation_mm**2 + 2.0 / 3.0 * rotation_mm**2)


def evaluate(rows, translation_mm, rotation_deg, radius_mm):
    covered = scored = confident = 0
    confident_error = 0.0
    for row in rows:
        add = misfit_cm2(translation_mm, rotation_deg, radius_mm[row["obj_id"]])
        value = nees(row, add)
        if value is not None:
            scored += 1
            covered += value <= CHI2_3_95
        variances = [row["var_x_cm2"], row["var_y_cm2"], row["var_z_cm2"]]
        if row["consistent"] and all(v + add <= 0.25 for v in variances):
            confident += 1
            confident_error += row["err_cm"]
    return {
        "objects": scored,
        "coverage95": covered / scored if scored else float("nan"),
        "confident": confident,
        "confident_mean_err_cm": confident_error / confident if confident else float("nan"),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("estimates_csv")
    parser.add_argument("models_info_json")
    parser.add_argument("--choice-scenes", required=True, help="comma-separated scene ids")
    parser.add_argument("--rotation-deg", type=float, default=0.25)
    parser.add_argument("--target", type=float, default=0.95)
    parser.add_argument("--step", type=float, default=0.5, help="grid step, mm")
    parser.add_argument("--max", type=float, default=6.0, help="largest candidate, mm")
    args = parser.parse_args()

    with open(args.models_info_json) as f:
        radius_mm = {int(k): 0.5 * v["diameter"] for k, v in json.load(f).items()}
    numeric = ["var_x_cm2", "var_y_cm2", "var_z_cm2", "cov_xy_cm2", "cov_xz_cm2", "cov_yz_cm2",
               "err_x_cm", "err_y_cm", "err_z_cm", "err_cm"]
    rows = []
    with open(args.estimates_csv) as f:
        for raw in csv.DictReader(f):
            if any(raw[k] == "" for k in numeric):
                continue  # not estimated
            row = {k: float(raw[k]) for k in numeric}
            row["scene_id"] = int(raw["scene_id"])
            row["obj_id"] = int(raw["obj_id"])
            row["consistent"] = raw["consistent"] == "1"
            rows.append(row)
    choice_ids = {int(s) for s in args.choice_scenes.split(",")}
    choice = [r for r in rows if r["scene_id"] in choice_ids]
    check = [r for r in rows if r["scene_id"] not in choice_ids]
    if not choice or not check:
        sys.exit("both the choice and the check scenes need estimated objects")

    print("translation_mm,set,objects,coverage95,confident,confident_mean_err_cm")
    chosen = None
    steps = int(round(args.max / args.step))
    for k in range(steps + 1):
        t = k * args.step
        for name, subset in (("choice", choice), ("check", check)):
            r = evaluate(subset, t, args.rotation_deg, radius_mm)
            print(f"{t:g},{name},{r['objects']},{r['coverage95']:.3f},{r['confident']},"
                  f"{r['confident_mean_err_cm']:.3f}")
        if chosen is None and evaluate(choice, t, args.rotation_deg,
                                       radius_mm)["coverage95"] >= args.target:
            chosen = t
    if chosen is None:
        sys.exit(f"no translation up to {args.max} mm covers {args.target} on the choice scenes")
    result = {name: evaluate(subset, chosen, args.rotation_deg, radius_mm)
              for name, subset in (("choice", choice), ("check", check))}
    print(f"chosen: {chosen:g} mm, {args.rotation_deg:g} deg; " + "; ".join(
        f"{name} scenes: {r['objects']} objects, coverage {r['coverage95']:.3f}, "
        f"{r['confident']} confident, mean error {r['confident_mean_err_cm']:.3f} cm"
        for name, r in result.items()))


if __name__ == "__main__":
    main()

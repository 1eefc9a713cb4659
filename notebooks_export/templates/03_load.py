%matplotlib inline
import json
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from IPython.display import display

report_dir = Path(REPORT_DIR)
VARIANCE_COLUMNS = ["var_x_cm2", "var_y_cm2", "var_z_cm2"]
# The covariance's off-diagonal entries (cov_xy_cm2, cov_xz_cm2, cov_yz_cm2) and the calibration
# columns (err_* per support-frame axis, nees = e^T S^-1 e, radius95_cm from the largest
# eigenvalue) are absent from reports of earlier versions, whose covariance was diagonal; an
# empty or infinite nees (a singular covariance) reads as NaN.
COVARIANCE_COLUMNS = ["cov_xy_cm2", "cov_xz_cm2", "cov_yz_cm2"]
NUMERIC_COLUMNS = ["px_count_all", "px_count_valid", "px_count_visib", "visib_fract",
                   *VARIANCE_COLUMNS, *COVARIANCE_COLUMNS, "err_cm", "err_x_cm", "err_y_cm",
                   "err_z_cm", "nees", "radius95_cm"]


def fmt(value, spec=".3g"):
    """A number for the text, or "undefined" for None / NaN / inf."""
    if value is None or not math.isfinite(float(value)):
        return "undefined"
    return format(value, spec)


def as_bool(column):
    """CSV booleans (1/0, true/false, empty) as True / False / NaN."""
    words = {"1": True, "1.0": True, "true": True, "0": False, "0.0": False, "false": False}
    return column.map(lambda v: words.get(str(v).strip().lower(), np.nan) if pd.notna(v) else np.nan)


objects_path = report_dir / "objects.csv"
if not objects_path.exists():
    raise FileNotFoundError(
        f"{objects_path} not found: run `clutterscope report DATASET --out {report_dir}` first")
objects = pd.read_csv(objects_path)
for column in NUMERIC_COLUMNS:
    if column in objects.columns:
        objects[column] = pd.to_numeric(objects[column], errors="coerce").replace(
            [np.inf, -np.inf], np.nan)
if "label" in objects.columns:
    objects["label"] = objects["label"].fillna("").astype(str)
# An object out of view (in_view 0: no pixel of its silhouette in the image) is neither hidden
# nor visible; as in the report, every figure is over the objects in view.
out_of_view = 0
if "in_view" in objects.columns:
    in_view = as_bool(objects["in_view"]).fillna(True).astype(bool)
    out_of_view = int((~in_view).sum())
    objects = objects[in_view].reset_index(drop=True)

has_estimates = all(column in objects.columns for column in VARIANCE_COLUMNS)
# The threshold applies to the largest axis variance: "largest <= T" means "every axis <= T".
# An object with any axis missing has no usable estimate (NaN).
objects["max_var_cm2"] = (objects[VARIANCE_COLUMNS].max(axis=1, skipna=False)
                          if has_estimates else np.nan)
if "err_cm" not in objects.columns:
    objects["err_cm"] = np.nan
objects["estimated"] = objects["max_var_cm2"].notna()
# The estimator's consistency checks (pixels seen through the estimate, ICP's shift from its
# belief): an estimate that fails them is never confident, whatever its variance. Reports of
# earlier versions have no column: every estimate passed.
objects["consistent"] = (as_bool(objects["consistent"]) == True  # noqa: E712 (NaN: no estimate)
                         if "consistent" in objects.columns else True)


def confident_at(frame, threshold):
    """The report's rule: the largest axis variance <= threshold and the consistency checks passed."""
    return (frame["max_var_cm2"] <= threshold) & frame["consistent"]


images_path = report_dir / "images.csv"
if images_path.exists():
    images = pd.read_csv(images_path)
    images["scene_visibility"] = pd.to_numeric(images["scene_visibility"], errors="coerce")
else:
    # Eq. 10 per image from the object rows: V^s = sum v_i / sum K_i.
    keys = ["split", "scene_id", "im_id"]
    grouped = objects.groupby(keys, sort=True)
    images = grouped[["px_count_visib", "px_count_valid"]].sum().reset_index()
    images["n_objects"] = grouped.size().values
    images["scene_visibility"] = (images["px_count_visib"]
                                  / images["px_count_valid"].where(images["px_count_valid"] > 0))
    images = images[keys + ["n_objects", "scene_visibility"]]
    print("images.csv not found: scene visibility computed from objects.csv")

summary_path = report_dir / "summary.json"
summary = json.loads(summary_path.read_text()) if summary_path.exists() else {}
if not isinstance(summary, dict):
    summary = {}

# With the Python module clutterscope importable (`cmake --install`, or PYTHONPATH=build/python)
# the report's decisions below come from the library: read_report runs the report's own analysis
# with the parameters above, so the numbers are the report's by construction. Without it they
# are recomputed here in pandas from the CSVs, with the same rules.
try:
    import clutterscope
except ImportError:
    clutterscope = None
library_report = None
if clutterscope is not None and has_estimates:
    library_report = clutterscope.read_report(
        report_dir, variance_threshold_cm2=VARIANCE_THRESHOLD_CM2,
        visibility_cutoff=VISIBILITY_CUTOFF, accurate_cm=ACCURATE_CM)
    print(f"decisions from the clutterscope module {clutterscope.__version__} (the report's "
          f"analysis)")
else:
    print("clutterscope module not importable: decisions recomputed here with pandas from the "
          "CSVs")

print(f"{len(objects)} objects in {len(images)} images; {int(objects['estimated'].sum())} with an "
      f"estimate, {int((objects['estimated'] & objects['err_cm'].notna()).sum())} of them with a "
      f"measured error" + (f"; {out_of_view} out of view, not analysed" if out_of_view else ""))
if not has_estimates:
    print("objects.csv has no estimate columns (a visibility-only folder): run "
          "`clutterscope report DATASET --out DIR` for the variance and threshold sections")
options = summary.get("options")
if isinstance(options, dict) and options:
    display(pd.DataFrame({"value": [v if v is not None else "undefined" for v in options.values()]},
                         index=list(options.keys())))

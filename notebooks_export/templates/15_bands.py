def defined(column, statistic):
    """median / mean over the defined values; NaN (printed as such) when there are none."""
    values = column.dropna()
    return getattr(values, statistic)() if len(values) else np.nan


def band_row(group):
    confident = confident_at(group, VARIANCE_THRESHOLD_CM2)
    confident_scored = confident & group["err_cm"].notna()
    off = confident_scored & (group["err_cm"] > ACCURATE_CM)
    return pd.Series({
        "objects": len(group),
        "estimated": int(group["estimated"].sum()),
        "median variance (cm²)": defined(group["max_var_cm2"], "median"),
        "mean variance (cm²)": defined(group["max_var_cm2"], "mean"),
        "median error (cm)": defined(group["err_cm"], "median"),
        "confident share": confident.sum() / group["estimated"].sum() if group["estimated"].any()
                           else np.nan,
        "confident off share": off.sum() / confident_scored.sum() if confident_scored.any()
                               else np.nan})


with_visibility = objects[objects["visib_fract"].notna()]
band_index = np.minimum((with_visibility["visib_fract"].clip(0.0, 1.0) * 10).astype(int), 9)
bands = pd.DataFrame([band_row(with_visibility[band_index == b]) for b in range(10)],
                     index=[f"{10 * b}–{10 * b + 10}%" for b in range(10)])
bands[["objects", "estimated"]] = bands[["objects", "estimated"]].astype(int)
display(bands.round(4))

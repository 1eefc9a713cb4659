PRECISION_TARGET = 0.95
scored = objects[objects["estimated"] & objects["err_cm"].notna()]
scored_accurate = scored["err_cm"] <= ACCURATE_CM


def threshold_check(threshold):
    """Precision, recall and F1 of "confident at threshold" against "error <= ACCURATE_CM", over
    the estimates with a measured error, as the report counts them."""
    confident = confident_at(scored, threshold)
    hits = int((confident & scored_accurate).sum())
    n_confident = int(confident.sum())
    n_accurate = int(scored_accurate.sum())
    precision = hits / n_confident if n_confident else np.nan
    recall = hits / n_accurate if n_accurate else np.nan
    if np.isnan(precision) or np.isnan(recall):
        f1 = np.nan
    else:
        f1 = 0.0 if precision + recall == 0 else 2 * precision * recall / (precision + recall)
    accepted_below = int((confident & (scored["visib_fract"] < VISIBILITY_CUTOFF)).sum())
    return {"threshold_cm2": threshold, "confident": n_confident, "accurate": n_accurate,
            "confident_and_accurate": hits, "precision": precision, "recall": recall, "f1": f1,
            "accepted_below_cutoff": accepted_below}


def log_sweep(low, high, per_decade, exact):
    """The report's sweep: log-spaced from low to high (4 significant digits), grid points within
    3% of an exact value dropped, the exact values added."""
    steps = math.ceil(math.log10(high / low) * per_decade - 1e-9)
    grid = [high if k == steps else float(f"{low * 10 ** (k / per_decade):.4g}")
            for k in range(steps + 1)]
    grid = [t for t in grid if not any(abs(t - e) <= 0.03 * e for e in exact)]
    return sorted(set(grid) | set(exact))


if library_report is not None:
    # The report's sweep and recommendation, computed by the library.
    recommendation = library_report.summary["thresholds"]["recommended"]
    PRECISION_TARGET = recommendation["min_precision"]
    sweep = library_report.sweep.rename(columns={"accepted": "confident",
                                                 "accepted_accurate": "confident_and_accurate"})
    for column in ["precision", "recall", "f1"]:
        sweep[column] = pd.to_numeric(sweep[column], errors="coerce")
    recommended = recommendation["largest_with_min_precision_cm2"]
    best_f1 = recommendation["best_f1_cm2"]
else:
    thresholds = log_sweep(0.01, 10.0, 10, [0.25, VARIANCE_THRESHOLD_CM2])
    sweep = pd.DataFrame([threshold_check(t) for t in thresholds])
    # Ascending thresholds, the later one winning ties, as the report recommends.
    recommended, best_f1, best_f1_value = None, None, None
    for row in sweep.itertuples():
        if not np.isnan(row.precision) and row.precision >= PRECISION_TARGET:
            recommended = float(row.threshold_cm2)
        if not np.isnan(row.f1) and (best_f1_value is None or row.f1 >= best_f1_value):
            best_f1, best_f1_value = float(row.threshold_cm2), row.f1
print(f"{len(scored)} estimates with a measured error, {int(scored_accurate.sum())} of them accurate")
print(f"largest threshold with precision >= {PRECISION_TARGET}: "
      f"{'undefined' if recommended is None else f'{recommended:.6g} cm²'}; F1 optimum at "
      f"{'undefined' if best_f1 is None else f'{best_f1:.6g} cm²'}")

fig, ax = plt.subplots(figsize=(7.5, 4))
for column, color in [("precision", "tab:blue"), ("recall", "tab:orange"), ("f1", "tab:green")]:
    ax.plot(sweep["threshold_cm2"], sweep[column], marker=".", color=color,
            label="F1" if column == "f1" else column)
ax.axvline(VARIANCE_THRESHOLD_CM2, color="tab:red",
           label=f"chosen {VARIANCE_THRESHOLD_CM2:g} cm²")
if recommended is not None:
    ax.axvline(recommended, color="tab:purple", linestyle="--",
               label=f"precision ≥ {PRECISION_TARGET}: {recommended:.3g} cm²")
if sweep[["precision", "recall"]].isna().all().all():
    ax.text(0.5, 0.5, "no estimates with a measured error", transform=ax.transAxes, ha="center")
ax.set_xscale("log")
ax.set_ylim(-0.02, 1.05)
ax.set_xlabel("variance threshold (cm²)")
ax.set_ylabel("share")
ax.set_title(f"Confident vs accurate (error ≤ {ACCURATE_CM:g} cm)")
ax.legend(loc="best", fontsize=8)
plt.show()

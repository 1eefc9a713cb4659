PRECISION_TARGET = 0.95
scored = objects[objects["estimated"] & objects["err_cm"].notna()]
scored_accurate = scored["err_cm"] <= ACCURATE_CM


def threshold_check(threshold):
    """Precision, recall and F1 of "max variance <= threshold" against "error <= ACCURATE_CM"."""
    confident = scored["max_var_cm2"] <= threshold
    hits = int((confident & scored_accurate).sum())
    n_confident = int(confident.sum())
    n_accurate = int(scored_accurate.sum())
    precision = hits / n_confident if n_confident else np.nan
    recall = hits / n_accurate if n_accurate else np.nan
    if np.isnan(precision) or np.isnan(recall):
        f1 = np.nan
    else:
        f1 = 0.0 if precision + recall == 0 else 2 * precision * recall / (precision + recall)
    all_estimated = objects[objects["estimated"]]
    accepted_below = int(((all_estimated["max_var_cm2"] <= threshold)
                          & (all_estimated["visib_fract"] < VISIBILITY_CUTOFF)).sum())
    return {"threshold_cm2": threshold, "confident": n_confident, "accurate": n_accurate,
            "confident_and_accurate": hits, "precision": precision, "recall": recall, "f1": f1,
            "accepted_below_cutoff": accepted_below}


thresholds = np.unique(np.concatenate([np.logspace(-2, 1, 31), [0.25, VARIANCE_THRESHOLD_CM2]]))
sweep = pd.DataFrame([threshold_check(t) for t in thresholds])
safe = sweep[sweep["precision"] >= PRECISION_TARGET]
recommended = float(safe["threshold_cm2"].max()) if not safe.empty else None
best_f1 = (float(sweep.loc[sweep["f1"].idxmax(), "threshold_cm2"])
           if sweep["f1"].notna().any() else None)
print(f"{len(scored)} estimates with a measured error, {int(scored_accurate.sum())} of them accurate")
print(f"largest threshold with precision >= {PRECISION_TARGET}: "
      f"{'undefined' if recommended is None else f'{recommended:.3g} cm²'}; F1 optimum at "
      f"{'undefined' if best_f1 is None else f'{best_f1:.3g} cm²'}")

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

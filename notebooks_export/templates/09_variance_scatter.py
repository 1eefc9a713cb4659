def correlation(x, y, method):
    """Correlation of two columns over rows where both are defined; None when undefined."""
    pair = pd.concat([x, y], axis=1).dropna()
    if len(pair) < 3 or pair.iloc[:, 0].nunique() < 2 or pair.iloc[:, 1].nunique() < 2:
        return None
    return float(pair.iloc[:, 0].corr(pair.iloc[:, 1], method=method))


estimated = objects[objects["estimated"] & objects["visib_fract"].notna()]
# A log axis has no 0: zero variances are drawn a decade below the smallest positive one.
positive = estimated.loc[estimated["max_var_cm2"] > 0, "max_var_cm2"]
VARIANCE_FLOOR_CM2 = min(positive.min() if len(positive) else 1.0, VARIANCE_THRESHOLD_CM2) / 10
at_floor = int((estimated["max_var_cm2"] < VARIANCE_FLOOR_CM2).sum())
if at_floor:
    print(f"{at_floor} estimates with variance below {VARIANCE_FLOOR_CM2:.2g} cm² (e.g. 0) are drawn at "
          f"{VARIANCE_FLOOR_CM2:.2g} cm²")
log_variance = np.log10(estimated["max_var_cm2"].where(estimated["max_var_cm2"] > 0))
for name, column in [("log variance", log_variance), ("position error", estimated["err_cm"])]:
    print(f"{name} vs visibility over {len(column.dropna())} objects: "
          f"Spearman {fmt(correlation(column, estimated['visib_fract'], 'spearman'))}, "
          f"Pearson {fmt(correlation(column, estimated['visib_fract'], 'pearson'))}")

fig, ax = plt.subplots(figsize=(7.5, 4.5))
plotted_variance = estimated["max_var_cm2"].clip(lower=VARIANCE_FLOOR_CM2)
no_error = estimated["err_cm"].isna()
if no_error.any():
    ax.scatter(estimated.loc[no_error, "visib_fract"], plotted_variance[no_error], s=25,
               color="lightgrey", edgecolors="grey", label="no ground truth")
if (~no_error).any():
    points = ax.scatter(estimated.loc[~no_error, "visib_fract"], plotted_variance[~no_error], s=25,
                        c=estimated.loc[~no_error, "err_cm"], cmap="viridis", vmin=0.0,
                        edgecolors="black", linewidths=0.3)
    fig.colorbar(points, ax=ax, label="position error (cm)")
if estimated.empty:
    ax.text(0.5, 0.5, "no estimates in this report", transform=ax.transAxes, ha="center")
ax.axhline(VARIANCE_THRESHOLD_CM2, color="tab:red",
           label=f"variance threshold {VARIANCE_THRESHOLD_CM2:g} cm²")
ax.axvline(VISIBILITY_CUTOFF, color="grey", linestyle=":",
           label=f"visibility cutoff {VISIBILITY_CUTOFF:.0%}")
ax.set_yscale("log")
ax.set_xlim(-0.02, 1.02)
ax.set_xlabel("object visibility $V_i$")
ax.set_ylabel("largest axis variance (cm²)")
ax.set_title("Belief variance against visibility")
ax.legend(loc="upper right", fontsize=8)
plt.show()

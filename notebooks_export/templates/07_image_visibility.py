MAX_BARS = 60
bars = images.sort_values(["split", "scene_id", "im_id"]).reset_index(drop=True)
if len(bars) > MAX_BARS:
    print(f"{len(bars)} images: drawing the {MAX_BARS} with the lowest scene visibility")
    bars = (bars.nsmallest(MAX_BARS, "scene_visibility")
            .sort_values(["split", "scene_id", "im_id"]).reset_index(drop=True))
several_splits = bars["split"].nunique() > 1
names = [(f"{row.split}/" if several_splits else "") + f"{row.scene_id}/{row.im_id}"
         for row in bars.itertuples()]
values = bars["scene_visibility"]
colors = ["tab:red" if v < VISIBILITY_CUTOFF else "tab:blue" for v in values.fillna(0.0)]

fig, ax = plt.subplots(figsize=(max(6.0, 0.25 * len(bars) + 2.0), 3.5))
positions = np.arange(len(bars))
ax.bar(positions, values.fillna(0.0), color=colors)
if len(bars) <= 30:
    for x, v in zip(positions, values):
        ax.text(x, (0.0 if pd.isna(v) else v) + 0.01, "n/a" if pd.isna(v) else f"{v:.0%}",
                ha="center", va="bottom", fontsize=7)
ax.axhline(VISIBILITY_CUTOFF, color="tab:red", linestyle="--", linewidth=1,
           label=f"visibility cutoff {VISIBILITY_CUTOFF:.0%}")
ax.set_xticks(positions)
ax.set_xticklabels(names, rotation=90, fontsize=7)
ax.set_ylim(0.0, 1.1)
ax.set_xlabel("image (scene/image id)")
ax.set_ylabel("scene visibility $V^s$")
ax.set_title("Scene visibility per image")
ax.legend(loc="lower right")
plt.show()

display(images.nsmallest(5, "scene_visibility"))

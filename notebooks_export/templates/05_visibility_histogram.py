visibility = objects["visib_fract"].dropna()
below_cutoff = int((visibility < VISIBILITY_CUTOFF).sum())
print(f"median object visibility {fmt(visibility.median())}; {below_cutoff} of {len(visibility)} "
      f"objects below the cutoff {VISIBILITY_CUTOFF:.0%}")

fig, ax = plt.subplots(figsize=(7, 3.5))
ax.hist(visibility, bins=np.linspace(0.0, 1.0, 21), color="tab:blue", edgecolor="white")
ax.axvline(VISIBILITY_CUTOFF, color="tab:red", linestyle="--",
           label=f"visibility cutoff {VISIBILITY_CUTOFF:.0%}")
ax.set_xlim(0.0, 1.0)
ax.set_xlabel("object visibility $V_i$ (fraction of the silhouette visible)")
ax.set_ylabel("objects")
ax.set_title("Object visibility")
ax.legend()
plt.show()

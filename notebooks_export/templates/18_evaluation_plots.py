if isinstance(evaluation, dict):
    methods = evaluation["methods"]
    for measure, entry in evaluation["by_visibility"].items():
        if entry is None:
            continue
        metrics = [metric for metric in BAND_METRICS
                   if metric in entry["methods"][methods[0]]["bands"][0]["average_recall"]]
        curve_path = report_dir / "evaluate" / (
            "by_visibility_curve.csv" if measure == "visib_fract"
            else "by_scene_visibility/by_visibility_curve.csv")
        curve = pd.read_csv(curve_path) if curve_path.exists() else None
        figure, axes = plt.subplots(2, len(metrics), figsize=(5 * len(metrics), 7.5), squeeze=False)
        width = 0.8 / len(methods)
        for column, metric in enumerate(metrics):
            bars, lines = axes[0][column], axes[1][column]
            bands = entry["methods"][methods[0]]["bands"]
            for m, method in enumerate(methods):
                values = [band["average_recall"].get(metric) for band in entry["methods"][method]["bands"]]
                values = [np.nan if value is None else value for value in values]
                bars.bar(np.arange(len(bands)) - 0.4 + width * (m + 0.5), values, width, label=method)
                if curve is not None:
                    rows = curve[(curve["method"] == method) & (curve["metric"] == metric)]
                    lines.plot(rows["centre"], pd.to_numeric(rows["average_recall"], errors="coerce"),
                               label=method)
            bars.set_xticks(np.arange(len(bands)))
            bars.set_xticklabels([band_label(band) for band in bands], rotation=45)
            bars.set_ylim(0, 1)
            bars.set_title(f"AR {metric.upper()} by {measure} band")
            bars.set_ylabel("average recall (share of targets)")
            bars.legend()
            lines.set_xlim(0, 1)
            lines.set_ylim(0, 1)
            lines.set_xlabel(f"{measure} (share 0-1)")
            lines.set_ylabel("average recall (share of targets)")
            lines.set_title(f"AR {metric.upper()} against {measure}" +
                            ("" if curve is not None else f" ({curve_path.name} not found)"))
            if curve is not None:
                lines.legend()
        figure.tight_layout()
        plt.show()

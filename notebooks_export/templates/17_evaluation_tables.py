evaluation = summary.get("evaluation")
BAND_METRICS = ["vsd", "mssd", "mspd"]


def band_label(band):
    return f"{100 * band['visibility_min']:.0f}–{100 * band['visibility_max']:.0f}%"


if not isinstance(evaluation, dict):
    print("no pose evaluation in this report: run `clutterscope report DATASET --results "
          "FILE.csv` for it")
else:
    methods = evaluation["methods"]
    print(f"methods: {', '.join(methods)} ({evaluation['bundled_method']}: the bundled "
          f"estimator)")
    for method in methods:
        recalls = evaluation["average_recalls"][method]
        print(f"AR {method}: vsd {fmt(recalls['vsd'])}, mssd {fmt(recalls['mssd'])}, "
              f"mspd {fmt(recalls['mspd'])}, mean {fmt(recalls['mean'])}")
    display(pd.DataFrame({method: evaluation["average_recalls"][method] for method in methods})
            .T.astype(float).round(4))
    for measure, entry in evaluation["by_visibility"].items():
        if entry is None:
            print(f"by {measure}: not in this report")
            continue
        rows, index = [], []
        first = entry["methods"][methods[0]]
        for b, band in enumerate(first["bands"]):
            for metric in BAND_METRICS:
                if metric not in band["average_recall"]:
                    continue
                index.append((band_label(band), metric))
                rows.append({"targets": band["targets"], **{
                    method: entry["methods"][method]["bands"][b]["average_recall"].get(metric)
                    for method in methods}})
        print(f"recall by {measure} band (average recall over the band's targets):")
        display(pd.DataFrame(rows, index=pd.MultiIndex.from_tuples(index, names=["band", "metric"]))
                .astype(float).round(4))
        for method in methods:
            for metric, correlation in entry["methods"][method]["correlations"].items():
                print(f"rho {measure} {method} {metric}: {fmt(correlation['spearman'])} "
                      f"[{fmt(correlation['interval_low'])}, {fmt(correlation['interval_high'])}] "
                      f"(n = {correlation['n']})")
            score = entry["methods"][method]["score"]
            if score is not None:
                best = score["all"]
                print(f"score {measure} {method}: recommended s {fmt(best['lowest_score_with_min_precision'])}, "
                      f"precision {fmt(best['precision'])}, recall {fmt(best['recall'])}")

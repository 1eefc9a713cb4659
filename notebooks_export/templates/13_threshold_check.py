if library_report is not None:
    # The chosen threshold's row of the report, computed by the library.
    row = library_report.summary["thresholds"]["chosen"]
    chosen = {"threshold_cm2": row["threshold_cm2"], "confident": row["accepted"],
              "accurate": row["accurate"], "confident_and_accurate": row["accepted_accurate"],
              "precision": np.nan if row["precision"] is None else row["precision"],
              "recall": np.nan if row["recall"] is None else row["recall"],
              "f1": np.nan if row["f1"] is None else row["f1"],
              "accepted_below_cutoff": row["accepted_below_cutoff"]}
else:
    chosen = threshold_check(VARIANCE_THRESHOLD_CM2)
estimated = objects[objects["estimated"]]
confident_now = confident_at(estimated, VARIANCE_THRESHOLD_CM2)
below = objects["visib_fract"] < VISIBILITY_CUTOFF
check = pd.DataFrame({"value": [
    f"{VARIANCE_THRESHOLD_CM2:g}", f"{VISIBILITY_CUTOFF:g}", f"{ACCURATE_CM:g}",
    len(objects), len(estimated), int(confident_now.sum()), chosen["confident"],
    chosen["confident"] - chosen["confident_and_accurate"],
    fmt(chosen["precision"]), fmt(chosen["recall"]), fmt(chosen["f1"]),
    int(below.sum()), chosen["accepted_below_cutoff"]]},
    index=["variance threshold (cm²)", "visibility cutoff", "accurate within (cm)", "objects",
           "objects with an estimate", "confident (acted on)", "confident with a measured error",
           "confident but off by more than ACCURATE_CM", "precision", "recall", "F1",
           "objects below the visibility cutoff", "confident below the visibility cutoff"])
display(check)
print(f"threshold check: precision {fmt(chosen['precision'])}, recall {fmt(chosen['recall'])}, "
      f"F1 {fmt(chosen['f1'])}, confident {int(confident_now.sum())}, "
      f"accepted below cutoff {chosen['accepted_below_cutoff']}")
print(f"with a measured error: {len(scored)} estimates, {chosen['accurate']} accurate, "
      f"{chosen['confident']} confident, {chosen['confident_and_accurate']} confident and accurate")

cutoffs = np.round(np.linspace(0.1, 0.9, 9), 2)
off = estimated["err_cm"] > ACCURATE_CM
converse = pd.DataFrame({
    "visibility below": [f"{c:.0%}" for c in cutoffs],
    "objects": [int((objects["visib_fract"] < c).sum()) for c in cutoffs],
    "with an estimate": [int((estimated["visib_fract"] < c).sum()) for c in cutoffs],
    "accepted": [int(((estimated["visib_fract"] < c) & confident_now).sum()) for c in cutoffs],
    "accepted & inaccurate": [int(((estimated["visib_fract"] < c) & confident_now & off).sum())
                              for c in cutoffs]})
display(converse)

if "confident" in estimated.columns:
    written = as_bool(estimated["confident"])
    known = written.notna()
    agree = int((written[known] == confident_now[known]).sum())
    print(f"the estimator's confident column agrees with VARIANCE_THRESHOLD_CM2 for {agree} of "
          f"{int(known.sum())} estimates")

import clutterscope

ds = clutterscope.Dataset("datasets/samples/tray6", scenes="1-2")
view = ds.image(1, 0)  # camera, GT instances, measured depth in metres
print(view.camera, len(view.objects), "GT instances, depth", view.depth.shape)
objects = clutterscope.visibility(ds, jobs=2)  # objects.csv as a DataFrame
print(objects[["scene_id", "gt_id", "label", "visib_fract"]])
report = clutterscope.report(ds, "tray6_report", jobs=2, particles=20, iterations=3)
print(report.objects[["label", "visib_fract", "err_cm", "confident"]])
print(report.decisions)  # recommended threshold, precision, coverage: the report's own

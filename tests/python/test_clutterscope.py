"""The Python module clutterscope against the CLI on the bundled samples: every function, each
DataFrame equal to the CLI's CSV for the same options, an error case per function with the CLI's
message, jobs=2 equal to jobs=1, a cancelled batch resumed, the notebook's numbers equal to the
report's."""

import json
import math
import os
import shutil
import signal
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from PIL import Image

import clutterscope
from conftest import (BUILD, EVALUATE_REFERENCE, FAST_ESTIMATE, FAST_ESTIMATE_FLAGS, SOURCE, cli_ok,
                      expect_cli_message, hermetic_env, run_cli)


def csv(path):
    return pd.read_csv(path)


def bad_copy(tray6, tmp_path):
    """tray6 with scene 1's first GT translation cut to two values (bad input: exit 3)."""
    root = tmp_path / "tray6_bad"
    shutil.copytree(tray6, root)
    scene_gt = root / "test/000001/scene_gt.json"
    gt = json.loads(scene_gt.read_text())
    gt["0"][0]["cam_t_m2c"] = gt["0"][0]["cam_t_m2c"][:2]
    scene_gt.write_text(json.dumps(gt))
    return root


# Dataset and image views.

def test_dataset_lists_the_selection_and_views_an_image(tray6):
    ds = clutterscope.Dataset(tray6, scenes="1-2")
    assert ds.scene_ids == sorted(int(p.name) for p in (tray6 / "test").iterdir())
    assert ds.scenes == [1, 2]
    assert ds.images == [(1, 0), (2, 0)]
    view = ds.image(1, 0)
    scene_gt = json.loads((tray6 / "test/000001/scene_gt.json").read_text())["0"]
    assert [o.obj_id for o in view.objects] == [entry["obj_id"] for entry in scene_gt]
    np.testing.assert_allclose(view.objects[2].cam_t_m2c, scene_gt[2]["cam_t_m2c"], rtol=1e-12)
    np.testing.assert_allclose(view.objects[2].cam_R_m2c.ravel(), scene_gt[2]["cam_R_m2c"],
                               rtol=1e-12)
    camera = json.loads((tray6 / "test/000001/scene_camera.json").read_text())["0"]
    np.testing.assert_allclose(view.camera.K.ravel(), camera["cam_K"], rtol=1e-12)
    # Depth in metres: the PNG's raw value times depth_scale is mm.
    raw = np.asarray(Image.open(view.depth_path), dtype=np.float64)
    assert view.depth.dtype == np.float32
    assert view.depth.shape == (view.camera.height, view.camera.width)
    np.testing.assert_allclose(view.depth, raw * view.camera.depth_scale / 1000.0, rtol=1e-6)


def test_dataset_error_has_the_cli_message(tray6, tmp_path):
    with pytest.raises(clutterscope.DatasetError) as error:
        clutterscope.Dataset(tray6, scenes="99")
    expect_cli_message(error.value, "visibility", tray6, "--scenes", "99", "--out",
                       tmp_path / "out")
    with pytest.raises(clutterscope.UsageError, match="--scenes"):
        clutterscope.Dataset(tray6, scenes="1-x")


# render_depth.

def test_render_depth_matches_the_cli_render(tray6, tmp_path):
    ds = clutterscope.Dataset(tray6)
    depth, labels = clutterscope.render_depth(ds, 1, 0)
    assert depth.dtype == np.float32 and labels.dtype == np.int32
    cli_ok("render", tray6, "--scene", "1", "--image", "0", "--out", tmp_path)
    depth_png = np.asarray(Image.open(next(tmp_path.glob("*depth*.png"))), dtype=np.float64)
    labels_png = np.asarray(Image.open(next(tmp_path.glob("*label*.png"))), dtype=np.int64)
    # The CLI writes millimetres rounded to 1 mm; the labels as they are.
    np.testing.assert_allclose(depth * 1000.0, depth_png, atol=0.5 + 1e-3)
    np.testing.assert_array_equal(labels, labels_png)
    # Labels are GT index + 1 (completely hidden instances have none).
    assert 0 < labels.max() <= len(ds.image(1, 0).objects)


def test_render_depth_error_has_the_cli_message(tray6, tmp_path):
    ds = clutterscope.Dataset(bad_copy(tray6, tmp_path))
    with pytest.raises(clutterscope.DatasetError) as error:
        clutterscope.render_depth(ds, 1, 0)
    expect_cli_message(error.value, "render", ds.path, "--scene", "1", "--image", "0", "--out",
                       tmp_path / "out")


# visibility.

def test_visibility_equals_the_cli_csv(tray6, tmp_path):
    cli_ok("visibility", tray6, "--scenes", "1-3", "--out", tmp_path / "cli", "-q", "--jobs", "1")
    one = clutterscope.visibility(clutterscope.Dataset(tray6), scenes="1-3", jobs=1,
                                  progress=False)
    pd.testing.assert_frame_equal(one, csv(tmp_path / "cli/objects.csv"))
    pd.testing.assert_frame_equal(one.attrs["images"], csv(tmp_path / "cli/images.csv"))
    assert one.attrs["summary"] == json.loads((tmp_path / "cli/summary.json").read_text())
    two = clutterscope.visibility(clutterscope.Dataset(tray6, scenes="1-3"), jobs=2,
                                  progress=False)
    pd.testing.assert_frame_equal(two, one)
    pd.testing.assert_frame_equal(two.attrs["images"], one.attrs["images"])


def test_visibility_bop_mode_equals_the_cli_csv(tray6, tmp_path):
    cli_ok("visibility", tray6, "--scenes", "2", "--mode", "bop19", "--delta-mm", "10", "--out",
           tmp_path / "cli", "-q", "--jobs", "1")
    frame = clutterscope.visibility(clutterscope.Dataset(tray6, scenes=[2]), mode="bop19",
                                    delta_mm=10, jobs=1, progress=False)
    pd.testing.assert_frame_equal(frame, csv(tmp_path / "cli/objects.csv"))


def test_visibility_error_has_the_cli_message(tray6, tmp_path):
    ds = clutterscope.Dataset(bad_copy(tray6, tmp_path), scenes="1")
    with pytest.raises(clutterscope.DatasetError) as error:
        clutterscope.visibility(ds, jobs=1, progress=False)
    expect_cli_message(error.value, "visibility", ds.path, "--scenes", "1", "--out",
                       tmp_path / "out", "-q", "--jobs", "1")
    with pytest.raises(clutterscope.UsageError, match="mode"):
        clutterscope.visibility(ds, mode="raycast", progress=False)


def test_cancelled_visibility_resumes_to_the_same_result(tray6, tmp_path):
    ds = clutterscope.Dataset(tray6)
    calls = []

    def interrupt(done, total):
        calls.append((done, total))
        if done >= 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        clutterscope.visibility(ds, jobs=1, out=tmp_path / "out", progress=interrupt)
    assert calls and calls[-1][1] == 6
    assert not (tmp_path / "out/objects.csv").exists()
    resumed_calls = []
    resumed = clutterscope.visibility(ds, jobs=1, out=tmp_path / "out",
                                      progress=lambda done, total: resumed_calls.append(done))
    whole = clutterscope.visibility(ds, jobs=2, progress=False)
    pd.testing.assert_frame_equal(resumed, whole)
    run = json.loads((tmp_path / "out/run.json").read_text())
    assert run["resumed"] >= 2, run


def test_ctrl_c_cancels_a_batch_that_resumes(tray6, tmp_path):
    """SIGINT while the batch runs (the main thread waits in C++): KeyboardInterrupt, and the
    finished images are resumed by the same call."""
    ds = clutterscope.Dataset(tray6)

    def press_ctrl_c(done, total):
        if done == 1:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        clutterscope.visibility(ds, jobs=1, out=tmp_path / "out", progress=press_ctrl_c)
    resumed = clutterscope.visibility(ds, jobs=1, out=tmp_path / "out", progress=False)
    pd.testing.assert_frame_equal(resumed, clutterscope.visibility(ds, jobs=1, progress=False))


# estimate.

def test_estimate_equals_the_cli_csv(tray6, tmp_path):
    cli_ok("estimate", tray6, "--scenes", "1", "--out", tmp_path / "cli", "-q", "--jobs", "1",
           *FAST_ESTIMATE_FLAGS, "--no-time", "--save-beliefs")
    estimates, beliefs = clutterscope.estimate(clutterscope.Dataset(tray6, scenes=1), jobs=1,
                                               time=False, beliefs=True, progress=False,
                                               **FAST_ESTIMATE)
    pd.testing.assert_frame_equal(estimates, csv(tmp_path / "cli/estimates.csv"))
    pd.testing.assert_frame_equal(estimates.attrs["bop_results"],
                                  csv(tmp_path / "cli/results_bop.csv"))
    cli_beliefs = csv(tmp_path / "cli/beliefs/test/000001/000000.csv")
    pd.testing.assert_frame_equal(beliefs.drop(columns=["split", "scene_id", "im_id"]),
                                  cli_beliefs)
    assert set(beliefs["scene_id"]) == {1} and set(beliefs["im_id"]) == {0}
    # jobs=2 gives the same table as jobs=1 (per-image random streams).
    two = clutterscope.estimate(clutterscope.Dataset(tray6, scenes=1), jobs=2, time=False,
                                progress=False, **FAST_ESTIMATE)
    pd.testing.assert_frame_equal(two, estimates)


def test_estimate_error_has_the_cli_message(tray6, tmp_path):
    detections = tmp_path / "detections.json"
    detections.write_text('[{"scene_id": 1, "image_id": 0, "category_id": 6, "score": 0.9}]')
    ds = clutterscope.Dataset(tray6, scenes=1)
    with pytest.raises(clutterscope.DatasetError) as error:
        clutterscope.estimate(ds, detections=detections, progress=False, **FAST_ESTIMATE)
    expect_cli_message(error.value, "estimate", tray6, "--scenes", "1", "--detections",
                       detections, "--out", tmp_path / "out", "-q", *FAST_ESTIMATE_FLAGS)
    with pytest.raises(clutterscope.UsageError) as usage:
        clutterscope.estimate(ds, particles=1, progress=False)
    expect_cli_message(usage.value, "estimate", tray6, "--scenes", "1", "--particles", "1",
                       "--out", tmp_path / "out2", "-q", exit_code=2)


# evaluate.

def test_evaluate_equals_the_cli_csv(evaluate_dataset, tmp_path):
    targets = EVALUATE_REFERENCE / "test_targets_bop19.json"
    results = [EVALUATE_REFERENCE / "results/small.csv", EVALUATE_REFERENCE / "results/mixed.csv"]
    cli_ok("evaluate", evaluate_dataset, "--targets", targets, "--results", *results,
           "--errors", "mssd,mspd", "--out", tmp_path / "cli", "-q", "--jobs", "1")
    ds = clutterscope.Dataset(evaluate_dataset, targets=targets)
    evaluation = clutterscope.evaluate(ds, results, errors=["mssd", "mspd"], jobs=1,
                                       progress=False)
    pd.testing.assert_frame_equal(evaluation.errors, csv(tmp_path / "cli/errors.csv"))
    pd.testing.assert_frame_equal(evaluation.by_visibility,
                                  csv(tmp_path / "cli/by_visibility_recall.csv"))
    for name, table in evaluation.tables.items():
        pd.testing.assert_frame_equal(table, csv(tmp_path / "cli" / f"{name}.csv"))
    scores = json.loads((tmp_path / "cli/scores.json").read_text())
    assert evaluation.scores_json == scores
    assert list(evaluation.scores["method"]) == list(scores)
    for row in evaluation.scores.itertuples():
        assert row.bop19_average_recall_mssd == scores[row.method]["bop19_average_recall_mssd"]


def test_evaluate_error_has_the_cli_message(evaluate_dataset, tmp_path):
    targets = EVALUATE_REFERENCE / "test_targets_bop19.json"
    bad = tmp_path / "bad.csv"
    bad.write_text("scene_id,im_id,obj_id,score,R,t,time\n0,1,8,0.5,1 0 0 0 1 0 0 0 1,0 0\n")
    ds = clutterscope.Dataset(evaluate_dataset, targets=targets)
    with pytest.raises(clutterscope.DatasetError) as error:
        clutterscope.evaluate(ds, bad, errors=["mssd"], progress=False)
    expect_cli_message(error.value, "evaluate", evaluate_dataset, "--targets", targets,
                       "--results", bad, "--errors", "mssd", "--out", tmp_path / "out", "-q")


# report, read_report and the notebook.

def test_report_equals_the_cli_report(report_dirs):
    cli, module, report = report_dirs
    for name in ("objects.csv", "images.csv"):
        pd.testing.assert_frame_equal(csv(module / name), csv(cli / name))
    cli_summary = json.loads((cli / "summary.json").read_text())
    assert report.summary == cli_summary
    pd.testing.assert_frame_equal(report.objects, csv(cli / "objects.csv"))
    assert (module / "clutter_report.ipynb").exists()


def test_read_report_decisions_are_the_library_s(report_dirs):
    cli, _, _ = report_dirs
    summary = json.loads((cli / "summary.json").read_text())
    report = clutterscope.read_report(cli)
    thresholds = summary["thresholds"]
    assert report.decisions["recommended_threshold_cm2"] == \
        thresholds["recommended"]["largest_with_min_precision_cm2"]
    assert report.decisions["precision"] == thresholds["chosen"]["precision"]
    assert report.decisions["recall"] == thresholds["chosen"]["recall"]
    coverage = [c for c in summary["calibration"]["all"]["coverage"] if c["nominal"] == 0.95]
    assert report.decisions["coverage"] == coverage[0]["observed"]
    assert len(report.sweep) == len(thresholds["sweep"])
    # The library's analysis again, with the report's own options, is the report's summary
    # (without the evaluation, which read_report does not redo).
    again = clutterscope.read_report(cli, variance_threshold_cm2=summary["options"][
        "variance_threshold_cm2"])
    assert again.summary == summary
    # Another threshold: `clutterscope thresholds` prints the same precision.
    looser = clutterscope.read_report(cli, variance_threshold_cm2=1.0)
    assert looser.decisions["variance_threshold_cm2"] == 1.0
    printed = cli_ok("thresholds", cli, "--variance-cm2", "1").stdout
    precision = looser.decisions["precision"]
    assert (f"{precision:.3f}" if precision is not None else "n/a") in printed, printed


def test_read_report_error_has_the_cli_message(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(clutterscope.DatasetError) as error:
        clutterscope.read_report(tmp_path / "empty")
    expect_cli_message(error.value, "thresholds", tmp_path / "empty", "--variance-cm2", "0.25")


def test_report_error_has_the_cli_message(tray6, tmp_path):
    ds = clutterscope.Dataset(bad_copy(tray6, tmp_path), scenes="1")
    with pytest.raises(clutterscope.DatasetError) as error:
        clutterscope.report(ds, tmp_path / "module", jobs=1, progress=False, **FAST_ESTIMATE)
    expect_cli_message(error.value, "report", ds.path, "--scenes", "1", "--out",
                       tmp_path / "cli", "-q", "--jobs", "1", *FAST_ESTIMATE_FLAGS)


def _executed(notebook, tmp_path, with_module):
    env = hermetic_env(tmp_path / "home")
    if with_module:
        env["PYTHONPATH"] = os.environ["PYTHONPATH"]
    else:
        env.pop("PYTHONPATH", None)
    completed = subprocess.run(
        ["jupyter", "nbconvert", "--to", "notebook", "--execute",
         "--ExecutePreprocessor.timeout=120", "--output-dir", str(tmp_path), "--output",
         "module" if with_module else "csv", str(notebook)],
        capture_output=True, text=True, env=env, cwd=tmp_path, check=False)
    assert completed.returncode == 0, completed.stderr
    executed = json.loads((tmp_path / ("module.ipynb" if with_module else "csv.ipynb"))
                          .read_text())
    return {cell["id"]: "".join("".join(o.get("text", "")) for o in cell.get("outputs", [])
                                if o.get("output_type") == "stream")
            for cell in executed["cells"]}


def _fmt(value):
    return "undefined" if value is None or not math.isfinite(value) else format(value, ".3g")


def test_notebook_numbers_are_the_report_s(report_dirs, tmp_path):
    cli, _, _ = report_dirs
    summary = json.loads((cli / "summary.json").read_text())
    # The notebook reads REPORT_DIR = "." (its own folder): run it where the report is.
    printed = _executed(cli / "clutter_report.ipynb", tmp_path, with_module=True)
    assert "clutterscope module" in printed["load"], printed["load"]
    chosen = summary["thresholds"]["chosen"]
    line = (f"threshold check: precision {_fmt(chosen['precision'])}, recall "
            f"{_fmt(chosen['recall'])}, F1 {_fmt(chosen['f1'])}")
    assert line in printed["threshold-check"], printed["threshold-check"]
    recommended = summary["thresholds"]["recommended"]["largest_with_min_precision_cm2"]
    expected = "undefined" if recommended is None else f"{recommended:.6g} cm²"
    assert f"precision >= {summary['options']['min_precision']}: {expected}" in \
        printed["threshold-sweep"], printed["threshold-sweep"]
    # Without the module the notebook still runs, from the CSVs.
    fallback = _executed(cli / "clutter_report.ipynb", tmp_path, with_module=False)
    assert "not importable" in fallback["load"], fallback["load"]


def test_write_notebook_writes_the_cli_notebook(report_dirs, tmp_path):
    cli, _, _ = report_dirs
    copy = tmp_path / "copy"
    shutil.copytree(cli, copy)
    (copy / "clutter_report.ipynb").unlink()
    written = clutterscope.write_notebook(copy, variance_threshold_cm2=1.0)
    shutil.copytree(cli, tmp_path / "by_cli")
    (tmp_path / "by_cli/clutter_report.ipynb").unlink()
    cli_ok("notebook", tmp_path / "by_cli", "--variance-threshold-cm2", "1")
    assert written.read_bytes() == (tmp_path / "by_cli/clutter_report.ipynb").read_bytes()


# Help, stubs, installation and the README example.

def test_every_function_documents_its_arguments_and_units():
    for function in (clutterscope.visibility, clutterscope.estimate, clutterscope.evaluate,
                     clutterscope.report, clutterscope.read_report, clutterscope.render_depth,
                     clutterscope.Dataset):
        doc = function.__doc__
        code = (function.__init__ if isinstance(function, type) else function).__code__
        names = code.co_varnames[:code.co_argcount + code.co_kwonlyargcount]
        for name in names:
            if name != "self":
                assert name in doc, (function.__name__, name)
    assert "(cm^2)" in clutterscope.estimate.__doc__ and "metres" in \
        clutterscope.render_depth.__doc__
    stub = Path(clutterscope.__file__).with_suffix(".pyi")
    assert stub.exists() and (stub.parent / "py.typed").exists()
    for name in clutterscope.__all__:
        assert name in stub.read_text(), name


def fresh_python(code, pythonpath, cwd):
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    return subprocess.run(["/usr/bin/python3", "-c", code], capture_output=True, text=True,
                          env=env, cwd=cwd, check=False)


def test_module_imports_from_the_build_tree_and_an_install_prefix(tmp_path):
    code = "import clutterscope; print(clutterscope.__file__, clutterscope.__version__)"
    built = fresh_python(code, os.environ["PYTHONPATH"], tmp_path)
    assert built.returncode == 0, built.stderr
    prefix = tmp_path / "prefix"
    install = subprocess.run([os.environ["CLUTTERSCOPE_CMAKE_COMMAND"], "--install", str(BUILD),
                              "--prefix", str(prefix), "--component", "runtime"],
                             capture_output=True, text=True, check=False)
    assert install.returncode == 0, install.stdout + install.stderr
    site = prefix / os.environ["CLUTTERSCOPE_PYTHON_INSTALL_DIR"]
    installed = fresh_python(code, site, tmp_path)
    assert installed.returncode == 0, installed.stderr
    assert installed.stdout.startswith(str(site / "clutterscope")), installed.stdout
    # Under the default prefix /usr/local that folder is on Debian's python3's own path.
    search = fresh_python("import sys; print('\\n'.join(sys.path))", None, tmp_path).stdout
    assert "/usr/local/" + os.environ["CLUTTERSCOPE_PYTHON_INSTALL_DIR"] in search.split("\n") \
        or os.environ["CLUTTERSCOPE_PYTHON_INSTALL_DIR"].startswith("lib/python3/"), search


def test_readme_example_runs_as_written(tmp_path):
    """tools/python/examples/readme.py is the README's Python example, quoted verbatim there; it
    runs from the repository root (here a folder whose datasets/ is the repository's, so that
    its report folder lands in the test's scratch)."""
    example = SOURCE / "tools/python/examples/readme.py"
    code = example.read_text()
    assert len([line for line in code.splitlines() if line.strip()]) <= 10
    (tmp_path / "datasets").symlink_to(SOURCE / "datasets")
    completed = subprocess.run(["/usr/bin/python3", str(example)], capture_output=True,
                               text=True, cwd=tmp_path, env=dict(os.environ), check=False)
    assert completed.returncode == 0, completed.stderr
    assert "recommended_threshold_cm2" in completed.stdout, completed.stdout
    readme = (SOURCE / "README.md").read_text()
    assert code.strip() in readme, "README.md does not quote tools/python/examples/readme.py"

"""clutterscope from Python: visibility and pose-belief analysis of cluttered scenes (BOP datasets).

The same jobs as the command line (`clutterscope visibility`, `estimate`, `evaluate`, `report`),
called in-process: keyword arguments are the CLI's options, tables come back as pandas
DataFrames with the columns and units of the CLI's CSV files, images as NumPy arrays.

    import clutterscope
    ds = clutterscope.Dataset("datasets/samples/tray6", scenes="1-2")
    objects = clutterscope.visibility(ds, jobs=2)          # = objects.csv
    estimates = clutterscope.estimate(ds, images="0")       # = estimates.csv

Errors: bad input data raises DatasetError with the CLI's message (the CLI exits with 3), bad
options UsageError (exit 2), rendering failures RenderError (exit 4). A batch runs with the GIL
released; Ctrl-C (KeyboardInterrupt) cancels it cleanly, and with `out=DIR` the finished images
stay in DIR, so the same call resumes where it stopped.
"""

import io
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from . import _clutterscope as _core
from ._clutterscope import DatasetError, RenderError, UsageError, __version__

__all__ = ["Dataset", "ImageView", "Camera", "GtInstance", "render_depth", "visibility",
           "estimate", "evaluate", "Evaluation", "report", "read_report", "Report",
           "write_notebook", "DatasetError", "UsageError", "RenderError", "__version__"]


def _id_text(ids, name):
    """An id selection as the CLI takes it: "1,2,5-7", an int, or an iterable of ints."""
    if ids is None:
        return ""
    if isinstance(ids, str):
        return ids
    if isinstance(ids, (int, np.integer)):
        return str(int(ids))
    try:
        return ",".join(str(int(i)) for i in ids)
    except (TypeError, ValueError):
        raise UsageError(f"{name}: expected ids such as '1,2,5-7' or a list of ints, "
                         f"got {ids!r}") from None


class Camera:
    """The pinhole camera of an image (OpenCV convention: x right, y down, z forward).

    K: 3x3 intrinsic matrix (pixels); width, height: image size (pixels); depth_scale: a raw
    depth PNG value times this is millimetres (BOP's depth_scale).
    """

    def __init__(self, entry):
        self.K = entry["K"]
        self.width = entry["width"]
        self.height = entry["height"]
        self.depth_scale = entry["depth_scale"]

    def __repr__(self):
        return (f"Camera(width={self.width}, height={self.height}, fx={self.K[0, 0]:.6g}, "
                f"fy={self.K[1, 1]:.6g}, cx={self.K[0, 2]:.6g}, cy={self.K[1, 2]:.6g})")


class GtInstance:
    """One ground-truth instance of scene_gt.json.

    gt_id: index in the image's scene_gt list; obj_id: model id; cam_R_m2c: 3x3 rotation model
    to camera; cam_t_m2c: translation model to camera (mm, as in BOP).
    """

    def __init__(self, entry):
        self.gt_id = entry["gt_id"]
        self.obj_id = entry["obj_id"]
        self.cam_R_m2c = entry["cam_R_m2c"]
        self.cam_t_m2c = entry["cam_t_m2c"]

    def __repr__(self):
        return f"GtInstance(gt_id={self.gt_id}, obj_id={self.obj_id})"


class ImageView:
    """One image of a Dataset: its camera, GT instances and measured depth.

    split, scene_id, im_id: the image's key; camera: Camera; objects: list of GtInstance;
    depth_path, rgb_path: files (None when absent); depth: the measured depth as a float32
    NumPy array in metres (0 = no return), read on first use.
    """

    def __init__(self, dataset, entry):
        self._dataset = dataset
        self.split = entry["split"]
        self.scene_id = entry["scene_id"]
        self.im_id = entry["im_id"]
        self.camera = Camera(entry["camera"])
        self.objects = [GtInstance(o) for o in entry["objects"]]
        self.depth_path = entry["depth_path"]
        self.rgb_path = entry["rgb_path"]
        self._depth = None

    @property
    def depth(self):
        """Measured depth, float32 array (height, width) in metres, 0 = no return."""
        if self._depth is None:
            self._depth = self._dataset._core.depth(self.scene_id, self.im_id)
        return self._depth

    def __repr__(self):
        return (f"ImageView(split={self.split!r}, scene_id={self.scene_id}, im_id={self.im_id}, "
                f"objects={len(self.objects)})")


class Dataset:
    """A BOP dataset folder with the CLI's dataset options.

    Args:
        path: the dataset folder (holds the models folder and the split folders).
        split: split folder to process (test, train_pbr, ...); CLI --split.
        scenes: scene ids to process: "1,2,5-7", an int or a list of ints (default: all scenes
            of the split); CLI --scenes.
        images: image ids within each scene, same forms; ranges select the ids that exist
            (default: all); CLI --images.
        split_type: BOP split type: reads folder SPLIT_TYPE and the root camera_TYPE.json
            where it exists; CLI --split-type.
        models_dir: models folder under path (models, models_eval, models_cad, ...); CLI
            --models-dir.
        targets: BOP test targets file (test_targets_bop19.json / _bop24.json); CLI --targets.

    Raises DatasetError (bad dataset files, an id that does not exist) and UsageError (a
    malformed id list) with the CLI's messages.
    """

    def __init__(self, path, split="test", *, scenes=None, images=None, split_type=None,
                 models_dir="models", targets=None):
        self.path = str(path)
        self.split = split
        self.selection = {"scenes": _id_text(scenes, "scenes"),
                          "images": _id_text(images, "images")}
        self.split_type = split_type or ""
        self.models_dir = models_dir
        self.targets = str(targets) if targets is not None else ""
        self._core = _core._Dataset(self.path, split, self.split_type, models_dir, self.targets,
                                    self.selection["scenes"], self.selection["images"])

    def select(self, scenes=None, images=None):
        """This dataset with another selection (None keeps this one's)."""
        return Dataset(self.path, self.split,
                       scenes=self.selection["scenes"] if scenes is None else scenes,
                       images=self.selection["images"] if images is None else images,
                       split_type=self.split_type, models_dir=self.models_dir,
                       targets=self.targets or None)

    @property
    def scene_ids(self):
        """Every scene id of the split folder, sorted (the selection does not filter them)."""
        return list(self._core.scene_ids())

    @property
    def scenes(self):
        """The selected scene ids, sorted."""
        return sorted({scene for scene, _ in self._core.images()})

    @property
    def images(self):
        """The selected images as (scene_id, im_id) pairs, in the order the jobs process them."""
        return [tuple(key) for key in self._core.images()]

    @property
    def models(self):
        """The models: list of dicts obj_id, label, diameter_mm, mesh_path."""
        return list(self._core.models())

    def image(self, scene_id, im_id):
        """The ImageView of one image (camera, GT instances, depth)."""
        return ImageView(self, self._core.view(int(scene_id), int(im_id)))

    def __iter__(self):
        for scene_id, im_id in self.images:
            yield self.image(scene_id, im_id)

    def __len__(self):
        return len(self.images)

    def __repr__(self):
        selection = ", ".join(f"{k}={v!r}" for k, v in self.selection.items() if v)
        return f"Dataset({self.path!r}, split={self.split!r}{', ' if selection else ''}{selection})"


def render_depth(ds, scene_id, im_id, *, pixel_center="half"):
    """The GT scene of one image rendered from its camera (EGL, headless).

    Args:
        ds: a Dataset.
        scene_id, im_id: the image.
        pixel_center: "half": K projects to (u + 0.5, v + 0.5) (GL, bop_toolkit's renderer);
            "integer": to (u, v) (OpenCV, BlenderProc).

    Returns (depth, labels): depth float32 (height, width) camera-frame Z in metres, 0 = no
    surface; labels int32, the front surface's GT index + 1, 0 = background. The GIL is
    released while rendering.
    """
    return _core.render_depth(ds._core, int(scene_id), int(im_id), pixel_center)


def _interactive():
    if "ipykernel" in sys.modules:
        return True
    return hasattr(sys.stderr, "isatty") and sys.stderr.isatty()


class _Progress:
    """progress=None: a tqdm bar when interactive (a terminal or a notebook), else none;
    True / False: always / never; a callable: called as progress(done, total) after each image
    (done counts the images resumed from an earlier run too)."""

    def __init__(self, progress, label):
        self.callback = progress if callable(progress) else None
        self.bar = None
        show = _interactive() if progress is None else progress is True
        if show:
            try:
                from tqdm.auto import tqdm
                self.bar = tqdm(desc=label, unit="image")
            except ImportError:
                self.bar = None

    def __call__(self, done, total, step=""):
        if self.bar is not None:
            if step and self.bar.desc != step:
                self.bar.set_description(step)
            self.bar.total = total
            self.bar.n = done
            self.bar.refresh()
        if self.callback is not None:
            self.callback(done, total)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _jobs(jobs):
    return max(1, os.cpu_count() or 1) if jobs is None else int(jobs)


def _read_csv(path):
    return pd.read_csv(path)


def _table(result, name):
    """A table of the job's result in memory (the bytes of OUT/name) as read_csv reads the file."""
    return pd.read_csv(io.StringIO(result["tables"][name]))


class _Out:
    """The run's output folder: `out` as given (kept: a later call into it resumes), else a
    temporary folder removed after the tables were read."""

    def __init__(self, out):
        self.temporary = None if out is not None else tempfile.TemporaryDirectory(
            prefix="clutterscope-")
        self.path = Path(out) if out is not None else Path(self.temporary.name) / "out"

    def __enter__(self):
        return self.path

    def __exit__(self, *exc):
        if self.temporary is not None:
            self.temporary.cleanup()


def _run(kind, ds, out, jobs, keep_going, progress, **options):
    bar = _Progress(progress, kind)
    try:
        result = getattr(_core, "run_" + kind)(
            ds._core, dict(out=str(out), jobs=_jobs(jobs), keep_going=bool(keep_going),
                           progress=bar, **options))
    finally:
        bar.close()
    return result


def _with_attrs(frame, **attrs):
    frame.attrs.update(attrs)
    return frame


def visibility(ds, mode="rendered", *, scenes=None, images=None, jobs=None, delta_mm=None,
               pixel_center="half", write_bop_info=False, masks=False, overlays=False,
               out=None, keep_going=False, progress=None):
    """Visibility of every GT instance (`clutterscope visibility`), as a DataFrame of objects.csv.

    Args:
        ds: a Dataset (its selection, unless scenes / images are given).
        mode: "rendered": Eq. 10 from the rendered GT scene (V_i = v_i / K_i); "bop19" or
            "bop18": bop_toolkit's calc_gt_info.py against the measured depth.
        scenes, images: ids to process ("1,2,5-7", an int or a list); default: ds's selection.
        jobs: worker threads, one render context and one core each (default: every core).
        delta_mm: BOP modes: depth tolerance in mm (default 15, bop_toolkit's).
        pixel_center: "half" (GL, bop_toolkit) or "integer" (OpenCV, BlenderProc).
        write_bop_info, masks, overlays: also write OUT/bop/.../scene_gt_info.json, BOP masks,
            overlay pictures (need out=).
        out: output folder; re-running into it resumes (default: a temporary folder).
        keep_going: record images with bad data in summary.json and continue.
        progress: None: a tqdm bar when interactive; True / False; or a callable(done, total),
            called with the GIL held (an exception in it cancels the batch).

    Returns objects.csv as a DataFrame (columns and units as the CSV: px_count_* in pixels,
    visib_fract a share 0-1); attrs["images"] is images.csv (scene_visibility V^s per image),
    attrs["summary"] summary.json. Raises DatasetError / UsageError / RenderError with the
    CLI's messages, KeyboardInterrupt when cancelled.
    """
    ds = ds.select(scenes, images) if scenes is not None or images is not None else ds
    with _Out(out) as folder:
        result = _run("visibility", ds, folder, jobs, keep_going, progress, mode=mode,
                      delta_mm=delta_mm, pixel_center=pixel_center,
                      write_bop_info=write_bop_info, masks=masks, overlays=overlays)
    return _with_attrs(_table(result, "objects.csv"), images=_table(result, "images.csv"),
                       summary=result["summary"])


def _read_beliefs(folder):
    frames = []
    for path in sorted((folder / "beliefs").glob("*/*/*.csv")):
        frame = _read_csv(path)
        frame.insert(0, "split", path.parent.parent.name)
        frame.insert(1, "scene_id", int(path.parent.name))
        frame.insert(2, "im_id", int(path.stem))
        frames.append(frame)
    if not frames:
        return pd.DataFrame(columns=["split", "scene_id", "im_id", "gt_id", "obj_id", "iteration",
                                     "x_mm", "y_mm", "z_mm", "weight"])
    return pd.concat(frames, ignore_index=True)


def estimate(ds, *, scenes=None, images=None, jobs=None, particles=100, iterations=15,
             gibbs_sweeps=5, icp_samples=20, variance_threshold_cm2=0.25,
             confidence_radius_cm=None, seed=1, observation="measured", detections=None,
             beliefs=False, time=True, out=None, keep_going=False, progress=None):
    """NBP scene estimation of every image (`clutterscope estimate`): estimates.csv as a DataFrame.

    Args:
        ds: a Dataset (its selection, unless scenes / images are given).
        scenes, images: ids to process; default: ds's selection.
        jobs: worker threads (default: every core).
        particles: M, Gaussian components per message.
        iterations: NBP iterations.
        gibbs_sweeps: Gibbs sweeps per product (kappa).
        icp_samples: K belief samples refined by ICP.
        variance_threshold_cm2: confident iff every axis variance is <= this (cm^2).
        confidence_radius_cm: also decide confident_radius: the 95% ellipsoid fits in a sphere
            of this radius (cm); None: not decided.
        seed: random seed (per-image streams).
        observation: "measured": the dataset's depth images; "synthetic": depth synthesised
            from the GT render through the sensor model.
        detections: BOP 2D detections JSON file; None: the synthetic detector.
        beliefs: also return the belief samples of every iteration (camera frame, mm).
        time: False leaves time_ms empty (and BOP time -1), so results are byte-reproducible.
        out, keep_going, progress: as in visibility().

    Returns estimates.csv as a DataFrame (x_mm, y_mm, z_mm in mm, camera frame; var_*_cm2 and
    cov_*_cm2 in cm^2; err_cm in cm; time_ms in ms); attrs["bop_results"] is results_bop.csv,
    attrs["summary"] summary.json. With beliefs=True a pair (estimates, beliefs): beliefs has
    split, scene_id, im_id and the columns of beliefs/SPLIT/SCENE/IMID.csv (gt_id, obj_id,
    iteration, x_mm, y_mm, z_mm, weight).
    """
    ds = ds.select(scenes, images) if scenes is not None or images is not None else ds
    with _Out(out) as folder:
        result = _run("estimate", ds, folder, jobs, keep_going, progress, particles=particles,
                      iterations=iterations, gibbs_sweeps=gibbs_sweeps, icp_samples=icp_samples,
                      variance_threshold_cm2=variance_threshold_cm2,
                      confidence_radius_cm=confidence_radius_cm, seed=seed,
                      observation=observation,
                      detections=None if detections is None else str(detections),
                      beliefs=beliefs, time=time)
        estimates = _with_attrs(_table(result, "estimates.csv"),
                                bop_results=_table(result, "results_bop.csv"),
                                summary=result["summary"])
        if beliefs:
            # One file per image (beliefs/SPLIT/SCENE/IMID.csv), not a table of the job.
            return estimates, _read_beliefs(folder)
        return estimates


class Evaluation:
    """The BOP 2019 pose evaluation of `clutterscope evaluate`.

    errors: errors.csv (one row per evaluated estimate and GT instance; mssd_mm in mm, mspd_px
    in pixels, vsd a share); scores: one row per method (results file) with bop_toolkit's
    average recalls (shares 0-1) and average time per image (s); by_visibility:
    by_visibility_recall.csv (recall per visibility band); tables: every CSV of the folder by
    name (by_visibility_curve, score_sweep, ...); scores_json: scores.json; summary:
    summary.json.
    """

    def __init__(self, result, folder):
        # errors.csv from memory; the by-visibility tables are written by the job's summary
        # (not tables of its batch), so they are read from the folder.
        self.tables = {path.stem: _read_csv(path) for path in sorted(folder.glob("*.csv"))}
        self.tables.update({Path(name).stem: _table(result, name)
                            for name in result["tables"] if "/" not in name})
        self.errors = self.tables["errors"]
        self.by_visibility = self.tables.get("by_visibility_recall")
        # scores.json is written beside the tables (bop_toolkit's keys), not a table.
        self.scores_json = json.loads((folder / "scores.json").read_text())
        keys = ["bop19_average_recall", "bop19_average_recall_vsd", "bop19_average_recall_mssd",
                "bop19_average_recall_mspd", "bop19_average_time_per_image"]
        self.scores = pd.DataFrame(
            [{"method": method, **{k: entry.get(k) for k in keys}}
             for method, entry in self.scores_json.items()])
        self.summary = result["summary"]

    def __repr__(self):
        return f"Evaluation(methods={list(self.scores['method'])}, errors={len(self.errors)} rows)"


def evaluate(ds, results, *, scenes=None, images=None, jobs=None, errors=None,
             vsd_delta_mm=None, scene_visibility_images=None, out=None, keep_going=False,
             progress=None):
    """BOP 2019 pose evaluation of results files (`clutterscope evaluate`).

    Args:
        ds: a Dataset; its targets file (default DATASET/test_targets_bop19.json) selects the
            images and objects.
        results: BOP 2019 results CSV files (a path or a list), each named in the outputs by
            its file name without .csv.
        scenes, images: ids to process; default: ds's selection.
        jobs: worker threads (default: every core).
        errors: the pose errors among "vsd", "mssd", "mspd" (default: all three when every
            target image has a depth image, else mssd and mspd).
        vsd_delta_mm: VSD's delta in mm (default: bop_toolkit's for the dataset's name).
        scene_visibility_images: an images.csv of visibility() (its attrs["images"] written to
            a file) to also analyse by the Eq. 10 scene visibility.
        out, keep_going, progress: as in visibility().

    Returns an Evaluation (errors, scores, by_visibility DataFrames). Raises DatasetError for a
    bad results file (naming file, line and field) with the CLI's message.
    """
    ds = ds.select(scenes, images) if scenes is not None or images is not None else ds
    files = [str(results)] if isinstance(results, (str, os.PathLike)) else [str(r) for r in results]
    with _Out(out) as folder:
        result = _run("evaluate", ds, folder, jobs, keep_going, progress, results=files,
                      errors=None if errors is None else list(errors),
                      vsd_delta_mm=vsd_delta_mm,
                      scene_visibility_images=None if scene_visibility_images is None
                      else str(scene_visibility_images))
        return Evaluation(result, folder)


class Report:
    """A clutter report folder: its tables and the report's decisions.

    objects: objects.csv (visibility joined with the estimates); images: images.csv; summary:
    summary.json, or the library's analysis for the options given to read_report; sweep: the
    threshold sweep (precision, recall, F1 per variance threshold in cm^2); bands: the
    visibility bands; decisions: the report's decisions as computed by the library (no
    re-derivation in Python):
        variance_threshold_cm2   the chosen threshold (cm^2)
        recommended_threshold_cm2  the largest swept threshold with precision >= min_precision
        min_precision            the precision the recommendation asks for
        precision, recall, f1    of the chosen threshold (confident vs error <= accurate_cm)
        confident, objects       counts
        coverage                 calibration: the observed share of estimates (with an error)
                                 whose error lies inside their 95% ellipsoid
    """

    def __init__(self, folder, summary):
        self.path = Path(folder)
        self.objects = _read_csv(self.path / "objects.csv")
        images = self.path / "images.csv"
        self.images = _read_csv(images) if images.exists() else None
        self.summary = summary
        thresholds = summary.get("thresholds", {})
        self.sweep = pd.DataFrame(thresholds.get("sweep", []))
        self.bands = pd.DataFrame(summary.get("bands", []))
        self.decisions = _decisions(summary)

    def __repr__(self):
        return f"Report({str(self.path)!r}, decisions={self.decisions})"


def _value(entry):
    """A summary.json statistic: a number, or {"value": ..., ...}; None when undefined."""
    if isinstance(entry, dict):
        return entry.get("value")
    return entry


def _decisions(summary):
    options = summary.get("options", {})
    thresholds = summary.get("thresholds", {})
    chosen = thresholds.get("chosen", {}) or {}
    recommended = thresholds.get("recommended", {}) or {}
    calibration = summary.get("calibration", {}) or {}
    coverage = None
    for entry in (calibration.get("all") or {}).get("coverage", []) or []:
        if abs(entry.get("nominal", 0) - 0.95) < 1e-9:
            coverage = entry.get("observed")
    counts = summary.get("counts", {})
    return {
        "variance_threshold_cm2": options.get("variance_threshold_cm2"),
        "recommended_threshold_cm2": _value(recommended.get("largest_with_min_precision_cm2")),
        "min_precision": recommended.get("min_precision", options.get("min_precision")),
        "precision": _value(chosen.get("precision")),
        "recall": _value(chosen.get("recall")),
        "f1": _value(chosen.get("f1")),
        "confident": counts.get("confident"),
        "objects": counts.get("objects"),
        "coverage": coverage,
    }


def read_report(folder, *, variance_threshold_cm2=None, visibility_cutoff=None,
                accurate_cm=None, confidence_radius_cm=None):
    """A report folder written by report() or `clutterscope report`.

    Args:
        folder: the report folder (holds objects.csv and summary.json).
        variance_threshold_cm2: confident iff every axis variance <= this (cm^2).
        visibility_cutoff: objects below this visibility (share 0-1) are barely visible.
        accurate_cm: an estimate is accurate when its position error is at most this (cm).
        confidence_radius_cm: the calibrated decision's sphere radius (cm).
        Each None: the report's own value; with any given, the library analyses the folder's
        tables again with those decisions (summary.json's content for them).

    Returns a Report. Raises DatasetError when the folder has no report (saying what to run).
    """
    folder = Path(folder)
    summary_path = folder / "summary.json"
    if not (folder / "objects.csv").exists() or not summary_path.exists():
        # The library's message, which says what to run.
        _core.analyse_report_folder(str(folder), 1.0, 0.25, 0.3, None, 1, {})
    summary = json.loads(summary_path.read_text())
    overrides = {"variance_threshold_cm2": variance_threshold_cm2,
                 "visibility_cutoff": visibility_cutoff, "accurate_cm": accurate_cm,
                 "confidence_radius_cm": confidence_radius_cm}
    if any(v is not None for v in overrides.values()):
        options = dict(summary.get("options", {}))
        options.update({k: v for k, v in overrides.items() if v is not None})
        summary = _core.analyse_report_folder(
            str(folder), float(options["accurate_cm"]), float(options["variance_threshold_cm2"]),
            float(options["visibility_cutoff"]), options.get("confidence_radius_cm"),
            int(options.get("seed", 1)), summary.get("run", {}))
    return Report(folder, summary)


def report(ds, out, *, scenes=None, images=None, jobs=None, accurate_cm=1.0,
           variance_threshold_cm2=0.25, visibility_cutoff=0.3, confidence_radius_cm=None,
           seed=1, mode="rendered", delta_mm=None, pixel_center="half", particles=100,
           iterations=15, gibbs_sweeps=5, icp_samples=20, observation="measured",
           detections=None, time=True, notebook=True, keep_going=False, progress=None):
    """The clutter report of a dataset (`clutterscope report DATASET --out OUT`).

    Runs visibility and estimation into OUT/visibility and OUT/estimate (finished images are
    reused, so an interrupted report resumes), then writes objects.csv, images.csv,
    summary.json, report.html, plots/ and clutter_report.ipynb into OUT.

    Args:
        ds: a Dataset (its selection, unless scenes / images are given).
        out: the report folder.
        accurate_cm: an estimate is accurate when its position error is at most this (cm).
        variance_threshold_cm2: confident iff every axis variance <= this (cm^2); also the
            estimator's.
        visibility_cutoff: objects below this visibility (share 0-1) count as barely visible.
        confidence_radius_cm: also the calibrated decision (cm); also the estimator's.
        seed: random seed of the estimator and of the bootstrap intervals.
        mode, delta_mm, pixel_center: the visibility step's (see visibility()).
        particles, iterations, gibbs_sweeps, icp_samples, observation, detections, time: the
            estimate step's (see estimate()).
        notebook: also write clutter_report.ipynb.
        jobs, keep_going, progress: as in visibility().

    Returns read_report(out).
    """
    ds = ds.select(scenes, images) if scenes is not None or images is not None else ds
    _run("report", ds, Path(out), jobs, keep_going, progress, accurate_cm=accurate_cm,
         variance_threshold_cm2=variance_threshold_cm2, visibility_cutoff=visibility_cutoff,
         confidence_radius_cm=confidence_radius_cm, seed=seed, mode=mode, delta_mm=delta_mm,
         pixel_center=pixel_center, particles=particles, iterations=iterations,
         gibbs_sweeps=gibbs_sweeps, icp_samples=icp_samples, observation=observation,
         detections=None if detections is None else str(detections), time=time,
         notebook=notebook)
    return read_report(out)


def write_notebook(folder, *, variance_threshold_cm2=0.25, visibility_cutoff=0.3,
                   accurate_cm=1.0):
    """Writes FOLDER/clutter_report.ipynb (`clutterscope notebook`); returns its path.

    variance_threshold_cm2 (cm^2), visibility_cutoff (share 0-1), accurate_cm (cm): the
    notebook's parameters cell.
    """
    evaluation = "evaluation" in json.loads((Path(folder) / "summary.json").read_text()) \
        if (Path(folder) / "summary.json").exists() else False
    return Path(_core.write_notebook(str(folder), variance_threshold_cm2, visibility_cutoff,
                                     accurate_cm, evaluation))

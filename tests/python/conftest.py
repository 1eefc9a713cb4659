"""Fixtures of the Python module's suite (tests/python, run by ctest as python.pytest).

ctest sets PYTHONPATH to the build tree's module and CLUTTERSCOPE_BINARY, CLUTTERSCOPE_SAMPLES_DIR,
CLUTTERSCOPE_SOURCE_DIR, CLUTTERSCOPE_BUILD_DIR, CLUTTERSCOPE_CMAKE_COMMAND and
CLUTTERSCOPE_PYTHON_INSTALL_DIR (tests/CMakeLists.txt). Every comparison is with the CLI run on
the same options: the module is a second front end over the same jobs.
"""

import os
import shutil
import subprocess
from pathlib import Path

import pytest


def _env(name):
    value = os.environ.get(name)
    if not value:
        raise RuntimeError(f"{name} is not set: run this suite through ctest (python.pytest)")
    return value


BINARY = Path(_env("CLUTTERSCOPE_BINARY"))
SAMPLES = Path(_env("CLUTTERSCOPE_SAMPLES_DIR"))
SOURCE = Path(_env("CLUTTERSCOPE_SOURCE_DIR"))
BUILD = Path(_env("CLUTTERSCOPE_BUILD_DIR"))
EVALUATE_REFERENCE = SOURCE / "tests/scene_estimation/data/bop_eval_reference/sample_a"

# Small estimator settings: the suite checks the front end, not the estimator.
FAST_ESTIMATE = {"particles": 20, "iterations": 3}
FAST_ESTIMATE_FLAGS = ["--particles", "20", "--iterations", "3"]


class CliRun:
    def __init__(self, completed):
        self.exit_code = completed.returncode
        self.stdout = completed.stdout
        self.stderr = completed.stderr


def run_cli(*args):
    """Runs the built clutterscope binary; its exit code, stdout and stderr."""
    completed = subprocess.run([str(BINARY), *map(str, args)], capture_output=True, text=True,
                               check=False)
    return CliRun(completed)


def cli_ok(*args):
    run = run_cli(*args)
    assert run.exit_code == 0, f"clutterscope {' '.join(map(str, args))}: {run.stderr}"
    return run


def expect_cli_message(exception, *args, exit_code=3):
    """The CLI on the same input exits with `exit_code` and prints the exception's message."""
    run = run_cli(*args)
    assert run.exit_code == exit_code, run.stderr
    assert f"error: {exception}" in run.stderr, (str(exception), run.stderr)


def hermetic_env(home):
    """What Jupyter, IPython and matplotlib write or read per user goes under `home`
    (tests/common/jupyter_run.cpp does the same for the C++ tests)."""
    env = dict(os.environ)
    for name in ("JUPYTER_PATH", "JUPYTER_CONFIG_PATH"):
        env.pop(name, None)
    for name, sub in [("HOME", ""), ("JUPYTER_CONFIG_DIR", "jupyter-config"),
                      ("JUPYTER_DATA_DIR", "jupyter-data"),
                      ("JUPYTER_RUNTIME_DIR", "jupyter-runtime"), ("IPYTHONDIR", "ipython"),
                      ("MPLCONFIGDIR", "matplotlib"), ("XDG_CACHE_HOME", "cache")]:
        env[name] = str(Path(home) / sub)
    env.update(MPLBACKEND="Agg", PYDEVD_DISABLE_FILE_VALIDATION="1", PYTHONDONTWRITEBYTECODE="1")
    return env


@pytest.fixture(scope="session")
def tray6():
    return SAMPLES / "tray6"


@pytest.fixture(scope="session")
def evaluate_dataset(tmp_path_factory):
    """ycbv_real with the reference's models_info.json and scene_gt_info.json (as
    tests/cli/evaluate_cli_support.hpp's write_evaluate_dataset)."""
    root = tmp_path_factory.mktemp("evaluate") / "ycbv_real"
    shutil.copytree(SAMPLES / "ycbv_real", root)
    shutil.copy(EVALUATE_REFERENCE / "models/models_info.json", root / "models/models_info.json")
    for scene in ("000000", "000003"):
        shutil.copy(EVALUATE_REFERENCE / "test" / scene / "scene_gt_info.json",
                    root / "test" / scene / "scene_gt_info.json")
    return root


@pytest.fixture(scope="session")
def report_dirs(tray6, tmp_path_factory):
    """The same report by the CLI and by the module: tray6 scenes 1-2, small estimator."""
    import clutterscope

    root = tmp_path_factory.mktemp("report")
    cli_ok("report", tray6, "--scenes", "1-2", "--out", root / "cli", "-q", "--jobs", "2",
           *FAST_ESTIMATE_FLAGS, "--no-time")
    report = clutterscope.report(clutterscope.Dataset(tray6, scenes="1-2"), root / "module",
                                 jobs=2, time=False, progress=False, **FAST_ESTIMATE)
    return root / "cli", root / "module", report

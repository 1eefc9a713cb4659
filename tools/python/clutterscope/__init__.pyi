# Type stubs of the package clutterscope (tools/python/clutterscope/__init__.py holds the
# docstrings: help(clutterscope.visibility) explains every argument and its unit).
import os
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Literal, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt
import pandas as pd

__version__: str

Ids = Union[str, int, Iterable[int], None]
PathLike = Union[str, os.PathLike[str]]
Progress = Union[None, bool, Callable[[int, int], None]]

class DatasetError(ValueError): ...
class UsageError(ValueError): ...
class RenderError(RuntimeError): ...

class Camera:
    K: npt.NDArray[np.float64]  # 3x3, pixels
    width: int
    height: int
    depth_scale: float  # raw depth PNG value * depth_scale = mm

class GtInstance:
    gt_id: int
    obj_id: int
    cam_R_m2c: npt.NDArray[np.float64]  # 3x3
    cam_t_m2c: npt.NDArray[np.float64]  # (3,), mm

class ImageView:
    split: str
    scene_id: int
    im_id: int
    camera: Camera
    objects: list[GtInstance]
    depth_path: Optional[str]
    rgb_path: Optional[str]
    @property
    def depth(self) -> npt.NDArray[np.float32]: ...  # (height, width), metres, 0 = no return

class Dataset:
    path: str
    split: str
    selection: dict[str, str]
    split_type: str
    models_dir: str
    targets: str
    def __init__(self, path: PathLike, split: str = ..., *, scenes: Ids = ..., images: Ids = ...,
                 split_type: Optional[str] = ..., models_dir: str = ...,
                 targets: Optional[PathLike] = ...) -> None: ...
    def select(self, scenes: Ids = ..., images: Ids = ...) -> Dataset: ...
    @property
    def scene_ids(self) -> list[int]: ...
    @property
    def scenes(self) -> list[int]: ...
    @property
    def images(self) -> list[tuple[int, int]]: ...
    @property
    def models(self) -> list[dict[str, Any]]: ...
    def image(self, scene_id: int, im_id: int) -> ImageView: ...
    def __iter__(self) -> Iterator[ImageView]: ...
    def __len__(self) -> int: ...

def render_depth(ds: Dataset, scene_id: int, im_id: int, *,
                 pixel_center: Literal["half", "integer"] = ...
                 ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]: ...

def visibility(ds: Dataset, mode: Literal["rendered", "bop19", "bop18"] = ..., *,
               scenes: Ids = ..., images: Ids = ..., jobs: Optional[int] = ...,
               delta_mm: Optional[float] = ..., pixel_center: Literal["half", "integer"] = ...,
               write_bop_info: bool = ..., masks: bool = ..., overlays: bool = ...,
               out: Optional[PathLike] = ..., keep_going: bool = ...,
               progress: Progress = ...) -> pd.DataFrame: ...

@overload
def estimate(ds: Dataset, *, scenes: Ids = ..., images: Ids = ..., jobs: Optional[int] = ...,
             particles: int = ..., iterations: int = ..., gibbs_sweeps: int = ...,
             icp_samples: int = ..., variance_threshold_cm2: float = ...,
             confidence_radius_cm: Optional[float] = ..., seed: int = ...,
             observation: Literal["measured", "synthetic"] = ...,
             detections: Optional[PathLike] = ..., beliefs: Literal[False] = ...,
             time: bool = ..., out: Optional[PathLike] = ..., keep_going: bool = ...,
             progress: Progress = ...) -> pd.DataFrame: ...
@overload
def estimate(ds: Dataset, *, scenes: Ids = ..., images: Ids = ..., jobs: Optional[int] = ...,
             particles: int = ..., iterations: int = ..., gibbs_sweeps: int = ...,
             icp_samples: int = ..., variance_threshold_cm2: float = ...,
             confidence_radius_cm: Optional[float] = ..., seed: int = ...,
             observation: Literal["measured", "synthetic"] = ...,
             detections: Optional[PathLike] = ..., beliefs: Literal[True],
             time: bool = ..., out: Optional[PathLike] = ..., keep_going: bool = ...,
             progress: Progress = ...) -> tuple[pd.DataFrame, pd.DataFrame]: ...

class Evaluation:
    errors: pd.DataFrame
    scores: pd.DataFrame
    by_visibility: Optional[pd.DataFrame]
    tables: dict[str, pd.DataFrame]
    scores_json: dict[str, Any]
    summary: dict[str, Any]

def evaluate(ds: Dataset, results: Union[PathLike, Sequence[PathLike]], *, scenes: Ids = ...,
             images: Ids = ..., jobs: Optional[int] = ...,
             errors: Optional[Sequence[Literal["vsd", "mssd", "mspd"]]] = ...,
             vsd_delta_mm: Optional[float] = ...,
             scene_visibility_images: Optional[PathLike] = ..., out: Optional[PathLike] = ...,
             keep_going: bool = ..., progress: Progress = ...) -> Evaluation: ...

class Report:
    path: Path
    objects: pd.DataFrame
    images: Optional[pd.DataFrame]
    summary: dict[str, Any]
    sweep: pd.DataFrame
    bands: pd.DataFrame
    decisions: dict[str, Any]

def read_report(folder: PathLike, *, variance_threshold_cm2: Optional[float] = ...,
                visibility_cutoff: Optional[float] = ..., accurate_cm: Optional[float] = ...,
                confidence_radius_cm: Optional[float] = ...) -> Report: ...

def report(ds: Dataset, out: PathLike, *, scenes: Ids = ..., images: Ids = ...,
           jobs: Optional[int] = ..., accurate_cm: float = ..., variance_threshold_cm2: float = ...,
           visibility_cutoff: float = ..., confidence_radius_cm: Optional[float] = ...,
           seed: int = ..., mode: Literal["rendered", "bop19", "bop18"] = ...,
           delta_mm: Optional[float] = ..., pixel_center: Literal["half", "integer"] = ...,
           particles: int = ..., iterations: int = ..., gibbs_sweeps: int = ...,
           icp_samples: int = ..., observation: Literal["measured", "synthetic"] = ...,
           detections: Optional[PathLike] = ..., time: bool = ..., notebook: bool = ...,
           keep_going: bool = ..., progress: Progress = ...) -> Report: ...

def write_notebook(folder: PathLike, *, variance_threshold_cm2: float = ...,
                   visibility_cutoff: float = ..., accurate_cm: float = ...) -> Path: ...

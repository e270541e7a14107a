"""Type stub of the `regbench` extension module (python/module.cpp). API: docs/python.md."""
from __future__ import annotations

import os
from typing import Any, Callable, Iterator, Mapping, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

_FloatArray = npt.NDArray[np.floating[Any]]
_PathLike = Union[str, os.PathLike[str]]

class _MethodInfo(TypedDict):
    name: str
    summary: str
    defaults: dict[str, Any]
    param_docs: dict[str, str]
    schema: dict[str, Any] | None

class _DataTag(TypedDict):
    pairs_file: str
    dataset: str
    protocol: str
    pairing: str
    seed: int | None
    content_hash: str

class _Metrics(TypedDict):
    mae_r: float
    mae_t: float
    mse_r: float
    mse_t: float
    rre: float
    rte: float
    ccd: float
    chamfer: float
    ccd_within_clip: bool
    overlap_rmse: float
    euler: str

class _RunSummary(TypedDict):
    out: str
    rows_written: int
    rows_skipped: int
    failures: int
    wall_seconds: float

def methods() -> list[_MethodInfo]:
    """Every registered method with its defaults, parameter docs and JSON schema."""

class _DataTagged:
    """What Pair and PairFile share: the pair file's data tag and its fields as shortcuts."""
    @property
    def data(self) -> _DataTag: ...
    @property
    def content_hash(self) -> str: ...
    @property
    def dataset(self) -> str: ...
    @property
    def protocol(self) -> str: ...
    @property
    def pairing(self) -> str: ...
    @property
    def seed(self) -> int | None: ...

class Pair(_DataTagged):
    """One pair of a PairFile; source/target are views of the PairFile's arrays (no copy)."""
    @property
    def index(self) -> int: ...
    @property
    def source(self) -> npt.NDArray[np.float64]:
        """(N, 3) float64 view."""
    @property
    def target(self) -> npt.NDArray[np.float64]:
        """(M, 3) float64 view."""
    @property
    def T_gt(self) -> npt.NDArray[np.float64]:
        """(4, 4): maps source into the target frame."""
    @property
    def source_overlap(self) -> npt.NDArray[np.uint8]: ...
    @property
    def target_overlap(self) -> npt.NDArray[np.uint8]: ...
    @property
    def source_overlap_ratio(self) -> float: ...
    @property
    def target_overlap_ratio(self) -> float: ...
    @property
    def overlap(self) -> float:
        """source_overlap_ratio."""
    @property
    def shape(self) -> str:
        """Mesh / scan name."""
    @property
    def category(self) -> str: ...
    @property
    def meta(self) -> dict[str, Any]: ...

class PairFile(_DataTagged):
    """A frozen HDF5 pair file, read and validated by the C++ reader."""
    def __init__(self, path: _PathLike) -> None:
        """Raises FileNotFoundError, or ValueError with the reader's message."""
    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> Pair: ...
    def __iter__(self) -> Iterator[Pair]: ...
    @property
    def path(self) -> str: ...
    @property
    def provenance(self) -> dict[str, Any]: ...

class AlignResult:
    """What align() returns."""
    @property
    def method(self) -> str: ...
    @property
    def params(self) -> dict[str, Any]: ...
    @property
    def T_target_source(self) -> npt.NDArray[np.float64]: ...
    @property
    def iterations(self) -> int: ...
    @property
    def stop_reason(self) -> str: ...
    @property
    def status(self) -> str:
        """"ok" or "failed"."""
    @property
    def message(self) -> str: ...
    @property
    def seconds(self) -> float: ...
    @property
    def cpu_seconds(self) -> float: ...
    @property
    def cpu_scope(self) -> str: ...
    @property
    def scale(self) -> float: ...
    @property
    def extra(self) -> dict[str, Any]: ...

def align(
    source: _FloatArray,
    target: _FloatArray,
    method: str = "cpd",
    params: Mapping[str, Any] | None = None,
    seed: int = 0,
    threads: int = 1,
    pair_index: int = 0,
    normalize: bool = False,
    *,
    max_points: int = 20000,
) -> AlignResult:
    """Registers source onto target with a built-in method (interpreter lock released)."""

def metrics(
    T_est: _FloatArray,
    T_gt: _FloatArray,
    source: _FloatArray,
    target: _FloatArray,
    euler: str = "zyx",
    source_overlap: npt.ArrayLike | None = None,
) -> _Metrics:
    """Every per-pair metric of docs/metrics.md."""

_CallableResult = Union[_FloatArray, Sequence[Sequence[float]], Mapping[str, Any]]
_MethodCallable = Callable[..., _CallableResult]
_MethodItem = Union[str, _MethodCallable, Tuple[str, _MethodCallable]]

def run(
    pairs: _PathLike | PairFile,
    methods: _MethodItem | Sequence[_MethodItem],
    out: _PathLike,
    params: Mapping[str, Mapping[str, Any]] | None = None,
    resume: bool = False,
    timeout: float | None = None,
    *,
    jobs: int = 1,
    threads: int = 1,
    euler: str = "zyx",
    max_points: int = 20000,
    downsample: bool = False,
    progress: bool = False,
) -> _RunSummary:
    """`regbench run` with Python callables fn(source, target, **params) as methods."""

def compare_methods(results: _PathLike | Sequence[_PathLike], a: str, b: str,
                    bootstrap: int = 2000, seed: int = 20230103) -> list[dict[str, Any]]:
    """Method a against method b on their common pairs, one dict per pair file (as `regbench
    report --versus a,b`): metrics holds per metric mean_a, mean_b, diff_mean (a - b), ci_lo,
    ci_hi and p_value (one paired bootstrap of the mean difference), differs, verdict, wins,
    ties, losses."""

def read_results(path: _PathLike, as_frame: bool | None = None) -> Any:
    """A pandas DataFrame (when pandas imports and as_frame is not False) or a list of dicts."""

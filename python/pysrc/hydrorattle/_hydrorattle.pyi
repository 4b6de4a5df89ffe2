"""Type stubs of the extension module (see ``hydrorattle`` for the documented API)."""

from os import PathLike
from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str

class StepError(RuntimeError):
    completed: int
    kind: str
    stage: Optional[str]
    index: Union[int, tuple[int, int], None]
    value: Optional[float]

class InvalidStateError(StepError): ...
class ConvergenceError(StepError): ...
class LinalgError(StepError): ...
class DegenerateError(StepError): ...
class NonFiniteError(StepError): ...
class OverlapError(StepError): ...
class UnstableError(StepError): ...
class ContactsFullError(StepError): ...
class UnsupportedError(StepError): ...

class SystemBusyError(RuntimeError): ...

class SceneError(ValueError):
    file: str
    line: Optional[int]
    column: Optional[int]

class Report:
    iterations: int
    velocity_iterations: int
    residual: float
    max_tension: float
    contacts: int
    wall_contacts: int
    contact_rounds: int
    noise_iterations: int
    steps: int
    retried_steps: int
    retry_substeps: int

_F64 = npt.NDArray[np.float64]

def mobility(
    positions: _F64,
    radii: _F64,
    viscosity: float = ...,
    hydro: str = ...,
    rotation: bool = ...,
    precision: str = ...,
    wall: Optional[float] = ...,
    box: Optional[tuple[float, float, float]] = ...,
    threads: int = ...,
) -> npt.NDArray[np.floating[Any]]: ...
def mobility_dot(
    positions: _F64,
    radii: _F64,
    forces: _F64,
    torques: Optional[_F64] = ...,
    viscosity: float = ...,
    hydro: str = ...,
    rotation: bool = ...,
    precision: str = ...,
    wall: Optional[float] = ...,
    box: Optional[tuple[float, float, float]] = ...,
    threads: int = ...,
    method: str = ...,
    tolerance: Optional[float] = ...,
) -> Any: ...
def load_scene_json(path: Union[str, PathLike[str]]) -> str: ...
def run_scene(
    path: Union[str, PathLike[str]],
    out: Union[str, PathLike[str]],
    checkpoint_every: Optional[float] = ...,
    max_storage: Optional[int] = ...,
) -> str: ...
def resume_run(
    out: Union[str, PathLike[str]],
    until: Optional[float] = ...,
    checkpoint_every: Optional[float] = ...,
    max_storage: Optional[int] = ...,
) -> str: ...
def read_trajectory(dir: Union[str, PathLike[str]]) -> dict[str, Any]: ...

class Core:
    @staticmethod
    def build(
        positions: _F64,
        radii: _F64,
        densities: _F64,
        bonds: npt.NDArray[np.int64],
        lengths: Optional[_F64],
        precision: str,
        params: Optional[dict[str, Any]],
    ) -> Core: ...
    @staticmethod
    def from_scene_file(path: Union[str, PathLike[str]]) -> Core: ...
    @staticmethod
    def from_scene_text(text: str, origin: str) -> Core: ...
    def step(
        self,
        n: int = ...,
        force: Optional[Callable[[_F64], Any]] = ...,
        callback: Optional[Callable[[], Any]] = ...,
        every: int = ...,
    ) -> Report: ...
    positions: _F64
    velocities: _F64
    spins: _F64
    radii: _F64
    densities: _F64
    bonds: npt.NDArray[np.int64]
    lengths: _F64
    tensions: Optional[_F64]
    time: float
    dt: float
    precision: str
    cell: Optional[tuple[float, float, float]]
    def set_state(
        self,
        positions: Optional[_F64] = ...,
        velocities: Optional[_F64] = ...,
        spins: Optional[_F64] = ...,
        time: Optional[float] = ...,
    ) -> None: ...
    def copy(self) -> Core: ...
    def save_json(self) -> str: ...
    @staticmethod
    def restore_json(text: str) -> Core: ...
    def state_bits(self) -> list[int]: ...

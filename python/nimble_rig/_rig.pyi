"""Type stubs of nimble_rig's compiled module (python/rig_module.cc and its py_*.cc files), for
editors. python.module (tests/python/test_stubs.py) checks that every function and class of the
module is here with the module's own parameter names."""
import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

PathLike = Union[str, os.PathLike]
#: Flight data: a rig log or identification CSV path, or channel name -> numpy array on one time
#: base ('t' [s] strictly increasing; 'p', 'v', 'phi', 'delta_f', 'delta_t', ... of
#: ident/flight_data.h).
Data = Union[PathLike, "Flight", Dict[str, np.ndarray]]
#: A model: a model file's path, or a dict with a model file's content (a relative vehicle path
#: taken from the current directory).
Model = Union[PathLike, Dict[str, Any]]

class ConfigError(ValueError):
    """A bad scenario or configuration value; str(e) is the rig's message. A value of an overrides
    dict has override True and no file or line (None)."""
    file: Optional[str]
    line: Optional[int]
    key: str
    value: str
    problem: str
    override: bool

class DataError(ValueError):
    """Bad flight data; str(e) is the rig's message. line is None where the data have no lines."""
    source: str
    line: Optional[int]
    row: int
    column: str
    problem: str

class Scenario:
    """A scenario loaded and checked as `rig run` loads it."""
    @property
    def file(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def seed(self) -> int: ...
    @property
    def duration_s(self) -> float: ...

class Flight:
    """One flight: the report and every channel's arrays."""
    @property
    def report(self) -> Dict[str, Any]: ...
    @property
    def channels(self) -> Dict[str, Dict[str, np.ndarray]]: ...
    def frame(self, channel: str) -> Any:
        """The channel as a pandas DataFrame indexed by t_s [s], a column per field ("euler_rad[0]")."""
        ...

def load_scenario(path: PathLike, overrides: Dict[str, Any] = ...) -> Scenario:
    """Loads a scenario with the same checks as `rig run`; overrides are --set values. Raises ConfigError."""
    ...

def fly(scenario: Scenario, seed: Optional[int] = None, clock: str = "inprocess",
        log: Optional[PathLike] = None, *, participants: Dict[str, Any] = ...) -> Flight:
    """Flies the scenario in process (the GIL released); SIGINT ends it with result interrupted.
    participants: {process: nimble_rig.Participant} flies each in place of that process."""
    ...

def sweep(scenario: Scenario, seeds: str = "1-10", vary: Dict[str, List[Any]] = ..., jobs: int = 1,
          dir: Optional[str] = None, envelopes: bool = False, report: Optional[str] = None) -> Dict[str, Any]:
    """Flies the scenario over seeds and parameter sets with `rig sweep`'s engine; its --json content
    (with envelopes: the percentiles of p [rad/s], v [m/s], phi_deg [deg] across seeds against t_s [s],
    as arrays); vary's values in the unit of their key (docs/configuration.md)."""
    ...

def identify(data: Data, *, structure: str = "lateral3", method: str = "wls", inputs: Optional[List[str]] = None,
             vehicle: Optional[str] = None, model_out: Optional[str] = None, states: str = "auto",
             sensing: Optional[str] = None, salvage: bool = False, rate_hz: Optional[float] = None,
             cutoff_hz: Optional[float] = None, order: Optional[int] = None,
             interpolation: str = "cubic", w0: float = 0.0, u0: float = 0.0, theta0: float = 0.0,
             phi0: float = 0.0, terms: Optional[Union[PathLike, List[str]]] = None,
             hover: Optional[List[Tuple[float, float]]] = None,
             manoeuvre: Optional[List[Tuple[float, float]]] = None,
             oe_segment_s: float = 2.0) -> Dict[str, Any]:
    """`rig identify --json`'s content, plus 'signals' and 'equations' (regressors, y, theta) as arrays;
    'eigenvalues' a complex array [1/s]. data may also be a Flight flown with log=; method 'wls', 'ols'
    or 'output-error'."""
    ...

def validate(model: Model, data: Data, *, closed_loop: bool = False, gains: Optional[str] = None,
             controller: Optional[str] = None, vehicle: Optional[str] = None, states: str = "auto",
             sensing: Optional[str] = None, salvage: bool = False, rate_hz: Optional[float] = None,
             cutoff_hz: Optional[float] = None, order: Optional[int] = None,
             interpolation: str = "cubic") -> Dict[str, Any]:
    """`rig validate [--closed-loop] --json`'s content, plus 't', 'measured' and 'predicted' or 'simulated'."""
    ...

def discrepancy(data: Union[Data, Sequence[Data]], *, model: Model, candidates: Optional[List[str]] = None,
                folds: Optional[int] = None, partial_f: Optional[float] = None,
                delay_max_s: Optional[float] = None, command_latency_s: Optional[float] = None,
                gains: Optional[str] = None, vehicle: Optional[str] = None, model_out: Optional[str] = None,
                states: str = "auto", sensing: Optional[str] = None, salvage: bool = False) -> Dict[str, Any]:
    """`rig discrepancy --json`'s content: the verdict, the named effects, the gap before and after."""
    ...

def loop(scenario: Union[PathLike, Scenario], *, model: Optional[Model] = None,
         gains: Union[None, str, Tuple[float, float], Dict[str, float]] = None,
         overrides: Dict[str, Any] = ..., on: Optional[str] = None, clock: Optional[str] = None,
         break_at: str = "actuator", all_sets: bool = False, box: Optional[str] = None,
         design: Optional[str] = None, design_name: str = "designed") -> Dict[str, Any]:
    """`rig loop --json`'s content; each loop with 'frequency_hz' [Hz], 'ratio' and 'tracking' (complex
    arrays), 'discrete' (A, B, C, D arrays, dt [s], 'dlti': scipy.signal.dlti, 'control' where
    python-control imports), 'closed_loop_poles' (complex [1/s]) with 'closed_loop_damping' and
    'closed_loop_natural_hz' [Hz]. gains: a set's name, 'KP,KD', (KP [1/rad], KD [s/rad]) or
    {'kp_per_rad': KP, 'kd_per_radps': KD}."""
    ...

def export_mcap(log: PathLike, out: PathLike, *, raw: bool = False, compression: str = "zstd",
                salvage: bool = False, vehicle: Optional[PathLike] = None, strict: bool = False) -> Dict[str, Any]:
    """Writes the rig log as MCAP; `rig export --format mcap --json`'s content. Messages beyond the
    vehicle's physical bounds are left out with a UserWarning (strict=True: DataError). Log time: the
    rig time [ns from the run's start]; fields in the units their names say."""
    ...


def log_bounds(log: PathLike, *, vehicle: Optional[PathLike] = None, salvage: bool = False) -> Dict[str, Any]:
    """The messages of a rig log beyond the vehicle's physical bounds: 'beyond_bounds' (per field: count,
    bound and first value in the field's unit, first_t_s [s]), 'text', 'offsets' (bytes into the log)."""
    ...

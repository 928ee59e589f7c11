"""Type stubs of nimble_rig's compiled module (python/rig_module.cc), for editors."""
from typing import Any, Dict, List, Optional

import numpy as np

class ConfigError(ValueError):
    """A bad scenario or configuration value; str(e) is the rig's message."""
    file: str
    line: int
    key: str
    value: str
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
    report: Dict[str, Any]
    channels: Dict[str, Dict[str, np.ndarray]]

def load_scenario(path: str, overrides: Dict[str, Any] = ...) -> Scenario:
    """Loads a scenario with the same checks as `rig run`; overrides are --set values. Raises ConfigError."""
    ...

def fly(scenario: Scenario, seed: Optional[int] = None, clock: str = "inprocess",
        log: Optional[str] = None) -> Flight:
    """Flies the scenario in process (the GIL released); SIGINT ends it with result interrupted."""
    ...

def sweep(scenario: Scenario, seeds: str = "1-10", vary: Dict[str, List[Any]] = ..., jobs: int = 1,
          dir: Optional[str] = None) -> Dict[str, Any]:
    """Flies the scenario over seeds and parameter sets with `rig sweep`'s engine; its --json content."""
    ...

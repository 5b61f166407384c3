"""The native half of the package (crate `situate_py`): the `situate` program, in-process skills."""

from typing import Any

def main(argv: list[str], interpreter: str | None = None, data_dir: str | None = None) -> int:
    """Runs the `situate` program with `argv` (first item: the program name); returns its exit code.

    The GIL is released while it runs; robot files may list `python:` skill files. `interpreter`
    runs the demo's sequencer (`sys.executable`); `data_dir` holds the shipped `demo/`, `maps/`
    and `examples/`.
    """

def version() -> str:
    """The version of the built-in `situate` program."""

def load_file(path: str) -> list[str]:
    """Loads a `python:` file's skill types as the program would; returns their descriptions."""

def map_json(path: str) -> str:
    """The building of a map file as JSON (what `situate map show` prints); `ValueError` if bad."""

def convert_check(value: Any, ty: str) -> Any:
    """Converts `value` to signal type `ty` and back, as a skill output would be."""

def declare(
    name: str,
    kind: str,
    priority: int,
    doc: str,
    inputs: list[tuple[str, str, str, bool, str]],
    outputs: list[tuple[str, str, str, str]],
    params: list[tuple[str, str, Any, float | None, float | None, str, str]],
    call: list[tuple[str, str]],
    positional: bool,
) -> Declaration:
    """Builds a skill declaration (raises `ValueError` naming the skill and port)."""

class Declaration:
    """A declared Python skill type."""

    @property
    def type_name(self) -> str: ...
    def describe(self) -> str: ...

class SkillStdout:
    """`sys.stdout` while Python skills exist: captures a skill's prints during its calls."""

    @property
    def wrapped(self) -> Any: ...
    def write(self, text: str) -> int: ...
    def flush(self) -> None: ...

class SharedArray:
    """The owner of an input array's memory (numpy's `base`)."""

    @property
    def __array_interface__(self) -> dict[str, Any]: ...
    def __len__(self) -> int: ...

class LocalRobot:
    """A robot file's manager in this process."""

    def __init__(
        self,
        path: str,
        clock: str | None = None,
        executor: str | None = None,
        resources: dict[str, Any] | None = None,
    ) -> None: ...
    @property
    def name(self) -> str: ...
    def step(self, cycles: int, record: list[str] = ...) -> str: ...
    def request(self, verb: str, payload: str) -> str: ...
    def events(self) -> list[str]: ...

class Elevator:
    """The elevator bank of a map file's building: the 2-D simulator's logic."""

    def __init__(self, path: str, seed: int) -> None: ...
    def cars(self) -> list[tuple[float, float, str, float, float]]: ...
    def press(
        self,
        label: int,
        floor: int,
        x: float,
        y: float,
        theta: float,
        reach: float,
        fov: float,
        now: float,
    ) -> bool: ...
    def step(self, now: float, dt: float, floor: int, x: float, y: float, theta: float) -> None: ...

class Traffic:
    """People walking and doors closing in a map file's building: the 2-D simulator's logic."""

    def __init__(self, path: str, seed: int, people: int, door_closures: bool) -> None: ...
    def people(self) -> list[tuple[int, float, float]]: ...
    def closed_door(self) -> tuple[int, int] | None: ...
    def place_person(self, k: int, floor: int, x: float, y: float, until: float) -> bool: ...
    def step(self, now: float, dt: float, floor: int, x: float, y: float) -> None: ...

"""In-process Python skills (`@situate.skill`) in a real manager's cycle, through the built wheel.

Each test writes a skill file and a robot file into its own directory and runs
them with `situate.LocalRobot` (the manager in this process, simulated clock),
so every check is exact and needs no network.
"""

from __future__ import annotations

import math
import sys
import textwrap
import types
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import pytest
from support import Write

import situate
from situate import _native

REPO = Path(__file__).resolve().parents[2]
RUNAWAY = REPO / "examples" / "python" / "runaway"


def robot_yaml(skills: str, *, python: str = "skills.py", devices: str = "") -> str:
    return (
        "robot: pytest\ncycle: {rate_hz: 100, clock: simulated, executor: serial}\n"
        f"python: [{python}]\n"
        + (f"devices:\n{textwrap.indent(textwrap.dedent(devices), '  ')}" if devices else "")
        + f"skills:\n{textwrap.indent(textwrap.dedent(skills), '  ')}"
    )


SONAR = """\
- name: sonar
  type: toy.sonar
  params: {room_m: 2.0, orbit_s: 0.5}
"""


def module_of(path: Path) -> types.ModuleType:
    """The module the loader made of a skill file (its latest import)."""
    found = [m for m in list(sys.modules.values()) if getattr(m, "__file__", None) == str(path)]
    assert found, f"{path} was not imported"
    return found[-1]


# ----- the cycle ---------------------------------------------------------------------


def test_the_runaway_example_computes_in_the_cycle_what_its_body_computes() -> None:
    run = situate.run(
        RUNAWAY / "robot.yaml", cycles=200, clock="simulated", record=["sonar.range", "drive"]
    )
    body = module_of(RUNAWAY / "runaway.py").runaway
    written = 0
    for cycle, (sonar, drive) in enumerate(
        zip(run.records["sonar.range"], run.records["drive"]), start=1
    ):
        if sonar.value is None:
            continue
        ranges = np.asarray(sonar.value, dtype=np.float32)
        expected = body(ranges, safe_distance=0.6)
        if expected is None:
            assert drive.cycle != cycle
        else:
            written += 1
            assert drive.cycle == cycle
            assert drive.writer == "runaway"
            assert drive.value == expected["drive"]  # exact: same f64 arithmetic
    assert written > 10, "the sonar's drifting box never came near: the test proves nothing"
    info = run.skills["runaway"]
    assert info.faulted is None
    assert info.timing.runs >= 190
    assert info.param("safe_distance").value == 0.6


def test_the_runaway_declaration_is_what_the_robot_files_expect() -> None:
    robot = situate.LocalRobot(RUNAWAY / "robot.yaml", clock="simulated")
    info = robot.skill("runaway")
    assert (info.type_name, info.kind, info.priority) == ("py.runaway", "sync", 50)
    assert [(p.name, p.signal, p.type) for p in info.inputs] == [
        ("sonar_range", "sonar.range", "f32[24]")
    ]
    assert [(p.name, p.type) for p in info.outputs] == [("drive", "{v: f64, w: f64}")]
    p = info.param("safe_distance")
    assert (p.type, p.default, p.min, p.max, p.unit) == ("f64", 0.5, 0.1, 3.0, "m")


def test_a_class_skill_keeps_its_state_per_instance(files: Write) -> None:
    files(
        "skills.py",
        """
        import situate

        @situate.skill(name="counter", outputs={"n": "i64"})
        class Counter:
            def __init__(self) -> None:
                self.n = 0

            def step(self, step: int = situate.param(1, min=1)) -> dict[str, int]:
                self.n += step
                return {"n": self.n}
        """,
    )
    path = files(
        "robot.yaml",
        robot_yaml(
            """
            - {name: one, type: counter, remap: {n: one.n}}
            - {name: three, type: counter, params: {step: 3}, remap: {n: three.n}}
            """
        ),
    )
    robot = situate.LocalRobot(path)
    robot.step(5)
    assert robot.query("one.n").value == 5
    assert robot.query("three.n").value == 15


def test_an_async_python_skill_delivers_its_results(files: Write) -> None:
    files(
        "skills.py",
        """
        import situate

        @situate.skill(name="src", outputs={"x": "f64"})
        def src() -> dict[str, float]:
            return {"x": 2.0}

        @situate.skill(name="slow.square", kind="async", outputs={"y": "f64"})
        def square(x: float) -> dict[str, float]:
            return {"y": x * x}
        """,
    )
    path = files(
        "robot.yaml", robot_yaml("- {name: src, type: src}\n- {name: sq, type: slow.square}\n")
    )
    robot = situate.LocalRobot(path)
    assert robot.skill("sq").kind == "async"
    robot.step(20)  # simulated clock: async bodies run in the cycle (lockstep)
    assert robot.query("y").value == 4.0
    assert robot.skill("sq").faulted is None


# ----- numpy, no copy ----------------------------------------------------------------


def test_array_inputs_are_read_only_numpy_views_of_the_signal(files: Write) -> None:
    skills = files(
        "skills.py",
        """
        import numpy as np
        import situate

        SEEN: dict[str, list] = {"a": [], "b": []}

        @situate.skill(name="reader", inputs={"r": situate.port("f32[24]", signal="sonar.range")})
        def reader(r, who: str = "a") -> None:
            SEEN[who].append(r)
        """,
    )
    path = files(
        "robot.yaml",
        robot_yaml(
            """
            - {name: ra, type: reader, params: {who: a}}
            - {name: rb, type: reader, params: {who: b}}
            """,
            devices=SONAR,
        ),
    )
    robot = situate.LocalRobot(path)
    readings = robot.record(["sonar.range"], 6)["sonar.range"]
    seen = module_of(skills).SEEN
    assert len(seen["a"]) == len(seen["b"]) >= 4
    for x, y in zip(seen["a"], seen["b"]):
        assert isinstance(x, np.ndarray)
        assert x.dtype == np.float32
        assert x.shape == (24,)
        assert not x.flags.owndata
        assert not x.flags.writeable
        assert isinstance(x.base, _native.SharedArray)
        # Two skills reading the same signal in one cycle see the same memory.
        assert np.shares_memory(x, y)
    with pytest.raises(ValueError, match="read-only"):
        seen["a"][-1][0] = 1.0
    # Arrays kept past their cycle still hold that cycle's values (the buffer lives on).
    last = [r.value for r in readings if r.value is not None][-len(seen["a"]) :]
    for x, value in zip(seen["a"], last):
        assert x.tolist() == pytest.approx(value, rel=0, abs=0)
    assert not np.shares_memory(seen["a"][0], seen["a"][-1])


def test_an_input_array_passed_through_is_shared_again_not_copied(files: Write) -> None:
    skills = files(
        "skills.py",
        """
        import situate

        OUT: list = []

        @situate.skill(
            name="pass",
            inputs={"r": situate.port("f32[24]", signal="sonar.range")},
            outputs={"copy": "f32[24]"},
        )
        def passthrough(r):
            return {"copy": r}

        @situate.skill(
            name="sink",
            inputs={"copy": "f32[24]", "r": situate.port("f32[24]", signal="sonar.range")},
        )
        def sink(copy, r) -> None:
            OUT.append((copy, r))
        """,
    )
    path = files(
        "robot.yaml",
        robot_yaml("- {name: pass, type: pass}\n- {name: sink, type: sink}\n", devices=SONAR),
    )
    robot = situate.LocalRobot(path)
    robot.step(4)
    out = module_of(skills).OUT
    assert out
    for copy, r in out:
        assert np.shares_memory(copy, r)


# ----- prints ------------------------------------------------------------------------


def test_prints_are_captured_per_skill_and_sent_when_verbose(
    files: Write, capfd: pytest.CaptureFixture[str]
) -> None:
    files(
        "skills.py",
        """
        import sys
        import situate

        @situate.skill(name="talker")
        def talker(word: str = "hello") -> None:
            print(word, "from", word)
            print("second", end="")
            print(" line", file=sys.stdout)
        """,
    )
    path = files(
        "robot.yaml",
        robot_yaml(
            """
            - {name: a, type: talker, params: {word: alpha}}
            - {name: b, type: talker, params: {word: beta}}
            """
        ),
    )
    robot = situate.LocalRobot(path)
    robot.step(2)
    a = robot.skill("a").prints
    b = robot.skill("b").prints
    assert [line for _, line in a] == ["alpha from alpha", "second line"] * 2
    assert [line for _, line in b] == ["beta from beta", "second line"] * 2
    assert [c for c, _ in a] == [1, 1, 2, 2]
    assert robot.events("print") == []  # not verbose: kept, not sent
    robot.set_verbose("b")
    robot.step(1)
    prints = [e for e in robot.events("print") if isinstance(e, situate.Print)]
    assert [(e.skill, e.line, e.cycle) for e in prints] == [
        ("b", "beta from beta", 3),
        ("b", "second line", 3),
    ]
    print("outside any skill")
    out = capfd.readouterr().out
    assert "outside any skill" in out
    assert "alpha" not in out
    assert "beta" not in out


# ----- faults ------------------------------------------------------------------------

FAULTY = """
import situate

@situate.skill(name="ticker", outputs={"t": "f64"})
def ticker(k: float = 1.0) -> dict[str, float]:
    return {"t": k}

@situate.skill(name="crashy", outputs={"y": "f64"})
def crashy(explode: bool = True) -> dict[str, float]:
    if explode:
        return {"y": helper()}
    return {"y": 42.0}

def helper() -> float:
    return 1 / 0
"""


def test_an_exception_faults_the_skill_with_its_traceback_and_the_cycle_goes_on(
    files: Write,
) -> None:
    skills = files("skills.py", FAULTY)
    path = files(
        "robot.yaml", robot_yaml("- {name: crashy, type: crashy}\n- {name: ticker, type: ticker}\n")
    )
    robot = situate.LocalRobot(path)
    robot.step(3)
    faults = robot.events("skill_faulted")
    assert len(faults) == 1
    fault = faults[0]
    assert isinstance(fault, situate.SkillFaulted)
    assert (fault.skill, fault.cycle) == ("crashy", 1)
    assert "ZeroDivisionError: division by zero" in fault.cause
    assert "Traceback (most recent call last)" in fault.cause
    assert f'File "{skills}", line 15, in helper' in fault.cause
    info = robot.skill("crashy")
    assert not info.active
    assert info.faulted == fault.cause
    # The other skill kept running every cycle.
    ticker = robot.query("t")
    assert (ticker.value, ticker.cycle) == (1.0, 3)
    # The sequencer fixes the cause and reactivates it.
    robot.set_param("crashy", "explode", False)
    assert robot.activate("crashy") == ["crashy"]
    robot.step(2)
    y = robot.query("y")
    assert (y.value, y.cycle) == (42.0, 5)
    info = robot.skill("crashy")
    assert info.active
    assert info.faulted is None


SLEEPY = """
import time
import situate

@situate.skill(name="ticker", outputs={"t": "f64"})
def ticker(k: float = 1.0) -> dict[str, float]:
    return {"t": k}

@situate.skill(name="sleepy", outputs={"y": "f64"})
def sleepy(nap_s: float = 0.0) -> dict[str, float]:
    time.sleep(nap_s)
    return {"y": 1.0}
"""


def test_a_python_body_over_its_budget_is_faulted_and_the_cycle_goes_on(files: Write) -> None:
    files("skills.py", SLEEPY)
    path = files(
        "robot.yaml",
        robot_yaml(
            "- {name: sleepy, type: sleepy, budget_ms: 100}\n- {name: ticker, type: ticker}\n"
        ),
    )
    robot = situate.LocalRobot(path)
    robot.step(2)
    robot.set_param("sleepy", "nap_s", 0.5)
    robot.step(3)
    (fault,) = robot.events("skill_faulted")
    assert isinstance(fault, situate.SkillFaulted)
    assert (fault.skill, fault.cycle) == ("sleepy", 3)
    assert "over its execution budget of 100 ms (`budget_ms`)" in fault.cause
    y = robot.query("y")
    assert (y.value, y.cycle) == (1.0, 2), "the late run's output was dropped"
    ticker = robot.query("t")
    assert (ticker.value, ticker.cycle) == (1.0, 5)


@pytest.mark.parametrize(
    ("ty", "returned", "port", "expected", "got"),
    [
        ("f64", "'fast'", "`y`", "expected f64", "got str"),
        ("f64", "True", "`y`", "expected f64", "got bool"),
        ("i64", "1.5", "`y`", "expected i64", "got float"),
        ("{v: f64, w: f64}", "{'v': 1.0, 'w': 'x'}", "`y.w`", "expected f64", "got str"),
        ("{v: f64, w: f64}", "{'v': 1.0}", "`y`", "expected {v: f64, w: f64}", "without `w`"),
        ("f32[3]", "[1.0, 2.0]", "`y`", "expected f32[3]", "got a list of 2"),
        ("f32[3]", "np.zeros((3, 2))", "`y`", "expected f32[3]", "float64 array of shape (3, 2)"),
        ("f64[]", "np.array(['a'])", "`y`", "expected f64[]", "<U1 array"),
        ("string", "b'raw'", "`y`", "expected string", "got bytes"),
    ],
)
def test_a_wrongly_typed_output_faults_naming_the_port(
    files: Write, ty: str, returned: str, port: str, expected: str, got: str
) -> None:
    files(
        "skills.py",
        f"""
        import numpy as np
        import situate

        @situate.skill(name="wrong", outputs={{"y": {ty!r}}})
        def wrong():
            return {{"y": {returned}}}
        """,
    )
    path = files("robot.yaml", robot_yaml("- {name: wrong, type: wrong}\n"))
    robot = situate.LocalRobot(path)
    robot.step(1)
    (fault,) = robot.events("skill_faulted")
    assert isinstance(fault, situate.SkillFaulted)
    assert "python skill `wrong`" in fault.cause
    assert f"output {port}" in fault.cause
    assert expected in fault.cause
    assert got in fault.cause
    assert robot.query("y").value is None


def test_unknown_outputs_and_non_dict_results_fault_with_the_declared_outputs(
    files: Write,
) -> None:
    files(
        "skills.py",
        """
        import situate

        @situate.skill(name="typo", outputs={"speed": "f64"})
        def typo() -> dict[str, float]:
            return {"sped": 1.0}

        @situate.skill(name="bare", outputs={"speed": "f64"})
        def bare() -> float:
            return 1.0
        """,
    )
    path = files(
        "robot.yaml",
        robot_yaml(
            "- {name: typo, type: typo, remap: {speed: a}}\n"
            "- {name: bare, type: bare, remap: {speed: b}}\n"
        ),
    )
    robot = situate.LocalRobot(path)
    robot.step(1)
    causes = {e.skill: e.cause for e in robot.events("skill_faulted")}  # type: ignore[union-attr]
    assert "unknown output `sped`; its outputs are `speed`" in causes["typo"]
    assert "returned a float; return a dict of outputs (`speed`) or None" in causes["bare"]


# ----- parameters --------------------------------------------------------------------


def test_parameters_are_typed_set_read_and_refused_out_of_range() -> None:
    robot = situate.LocalRobot(RUNAWAY / "robot.yaml", clock="simulated")
    assert robot.get_param("runaway", "safe_distance") == 0.6
    robot.set_param("runaway", "safe_distance", 3)  # an int is taken as f64
    assert robot.get_param("runaway", "safe_distance") == 3.0
    with pytest.raises(situate.BadParam, match=r"expects a number in \[0.1, 3.0\], got 7"):
        robot.set_param("runaway", "safe_distance", 7.0)
    with pytest.raises(situate.BadParam, match='got "far"'):
        robot.set_param("runaway", "safe_distance", "far")
    with pytest.raises(situate.UnknownParam, match="safe_distanse"):
        robot.set_param("runaway", "safe_distanse", 1.0)
    assert robot.get_param("runaway", "safe_distance") == 3.0


def test_the_body_sees_the_parameter_it_was_set_to(files: Write) -> None:
    files(
        "skills.py",
        """
        import situate

        @situate.skill(name="gain", outputs={"y": "f64"})
        def gain(
            g: float = situate.param(2.0, min=0.0, max=10.0),
            label: str = "x",
            on: bool = True,
            n: int = 3,
        ) -> dict[str, float]:
            assert isinstance(label, str) and isinstance(on, bool) and isinstance(n, int)
            return {"y": g * n if on else -1.0}
        """,
    )
    path = files("robot.yaml", robot_yaml("- {name: gain, type: gain}\n"))
    robot = situate.LocalRobot(path)
    robot.step(1)
    assert robot.query("y").value == 6.0
    robot.set_param("gain", "g", 0.5)
    robot.set_param("gain", "n", 4)
    robot.step(1)
    assert robot.query("y").value == 2.0
    robot.set_param("gain", "on", False)
    robot.step(1)
    assert robot.query("y").value == -1.0
    with pytest.raises(situate.BadParam):
        robot.set_param("gain", "n", 1.5)
    assert robot.skill("gain").faulted is None


# ----- run() -------------------------------------------------------------------------


def test_run_returns_the_summary_events_and_records(files: Write) -> None:
    files("skills.py", FAULTY)
    path = files(
        "robot.yaml", robot_yaml("- {name: crashy, type: crashy}\n- {name: ticker, type: ticker}\n")
    )
    result = situate.run(path, cycles=4, record=["t"])
    assert result.stats.cycle == 4
    assert result.skills["crashy"].faulted is not None
    assert result.skills["ticker"].timing.runs == 4
    assert [r.cycle for r in result.records["t"]] == [1, 2, 3, 4]
    kinds = [type(e).__name__ for e in result.events]
    assert "SkillFaulted" in kinds


def test_values_convert_both_ways_exactly() -> None:
    assert _native.convert_check(1.5, "f64") == 1.5
    assert _native.convert_check(3, "f64") == 3.0
    assert _native.convert_check(np.float32(0.25), "f64") == 0.25
    assert _native.convert_check(np.int64(7), "i64") == 7
    assert _native.convert_check(np.bool_(True), "bool") is True
    back = _native.convert_check([1, 2.5], "f64[]")
    assert isinstance(back, np.ndarray)
    assert back.tolist() == [1.0, 2.5]
    assert _native.convert_check(np.arange(4, dtype=np.int32), "i64[4]").tolist() == [0, 1, 2, 3]
    strided = np.arange(8, dtype=np.float64)[::2]
    assert _native.convert_check(strided, "f32[]").tolist() == [0.0, 2.0, 4.0, 6.0]
    rec = _native.convert_check({"v": 1, "w": -0.5, "tag": "x"}, "{v: f64, w: f64, tag: string}")
    assert rec == {"v": 1.0, "w": -0.5, "tag": "x"}
    assert _native.convert_check(b"\x00\xff", "bytes") == b"\x00\xff"
    with pytest.raises(TypeError, match="unknown field `z`"):
        _native.convert_check({"v": 1.0, "w": 2.0, "z": 0}, "{v: f64, w: f64}")
    with pytest.raises(TypeError, match=r"at `\[1\]`: expected f64, got str"):
        _native.convert_check([1.0, "x"], "f64[]")
    with pytest.raises(TypeError, match="float64 array"):
        _native.convert_check(np.ones(2), "i64[]")
    assert math.isinf(_native.convert_check(float("inf"), "f64"))


def test_declarations_read_from_signatures() -> None:
    @situate.skill(name="t.decl", priority=7, outputs={"out": situate.port("f64", signal="o.x")})
    def body(
        x: float,
        arr: Annotated[Any, "f32[]"],
        maybe: int | None = None,
        gain: float = 2,
        name: str = situate.param("n", doc="a name"),
    ) -> None:
        """Docs."""

    assert body.inputs == {"x": "f64", "arr": "f32[]", "maybe": "i64"}
    assert body.params == {"gain": 2.0, "name": "n"}
    assert body.outputs == {"out": "f64"}
    text = body.describe()
    assert "t.decl (sync, priority 7)" in text
    assert "in  maybe: i64 (optional)" in text
    assert "out out: f64 -> o.x" in text
    assert "param gain: f64 = 2" in text
    assert body.doc == "Docs."
    assert body(1.0, None) is None  # the plain function


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: situate.skill(name="k", kind="device")(lambda: None), 'kind must be "sync"'),
        (lambda: situate.skill(lambda x: None), "input `x` has no type"),
        (lambda: situate.skill(lambda x: None, inputs={"x": "f33"}), "bad type `f33`"),  # type: ignore[call-overload]
        (lambda: situate.skill(lambda: None, outputs={"y": "{a: }"}), "output `y`: bad type"),  # type: ignore[call-overload]
        (lambda: situate.skill(lambda g=situate.param(5.0, min=0, max=1): None), "parameter `g`"),
        (lambda: situate.skill(lambda g=[1]: None), "not a parameter type"),
        (lambda: situate.skill(lambda *a: None), "*a"),
        (lambda: situate.skill(lambda: None, inputs={"x": "f64"}), "no argument named `x`"),  # type: ignore[call-overload]
    ],
)
def test_bad_declarations_are_refused_naming_the_skill(
    make: Callable[[], Any], message: str
) -> None:
    with pytest.raises(situate.SkillDeclarationError, match="skill `") as info:
        make()
    assert message in str(info.value)


def test_the_python_and_rust_runaways_agree_bit_for_bit_over_1000_cycles(files: Write) -> None:
    path = files(
        "robot.yaml",
        f"""\
        robot: agree
        cycle: {{rate_hz: 100, clock: simulated, executor: serial}}
        python: [{RUNAWAY / "runaway.py"}]
        devices:
          - {{name: sonar, type: toy.sonar, params: {{room_m: 2.0, orbit_s: 1.3}}}}
        skills:
          - name: rs
            type: rust.runaway
            params: {{safe_distance: 0.9}}
            remap: {{drive: rs.drive}}
          - name: py
            type: py.runaway
            params: {{safe_distance: 0.9}}
            remap: {{drive: py.drive}}
        """,
    )
    records = situate.LocalRobot(path).record(["rs.drive", "py.drive"], 1000)
    written = 0
    for rs, py in zip(records["rs.drive"], records["py.drive"]):
        assert (rs.cycle, rs.value) == (py.cycle, py.value)
        if rs.value is not None:
            written += 1
            assert rs.value["v"].hex() == py.value["v"].hex()
            assert rs.value["w"].hex() == py.value["w"].hex()
    assert written > 100

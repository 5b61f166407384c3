"""The installed package on its own: its version, `python -m situate`, the shipped demo run from
anywhere with the package's own interpreter, a C skill built with the shipped CMake package, and
the program's exit codes through the wheel."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from support import REPO, free_port, situate, situate_program

import situate as situate_pkg
from situate import _cli


def test_the_version_is_the_programs() -> None:
    assert situate_pkg.__version__ == situate_pkg.version()
    assert "__version__" in situate_pkg.__all__


def test_python_dash_m_runs_the_program(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "situate", "--version"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"situate {situate_pkg.__version__}"


def test_the_demo_maps_and_examples_ship_with_the_package() -> None:
    data = _cli.data_dir()
    assert data is not None, "the wheel ships situate/_data (scripts/package-data.sh)"
    shipped = ["demo/robot.yaml", "demo/deliver.py", "maps/small.yaml", "examples/toybot.yaml"]
    # The program is the package beside demo/deliver.py: every module of it ships.
    shipped += [str(p.relative_to(REPO)) for p in (REPO / "demo" / "courier").rglob("*.py")]
    shipped += ["cmake/situateConfig.cmake", "include/situate.h", "include/situate.hpp"]
    for path in shipped:
        assert (data / path).is_file(), path
    # Reachable without the private module: `situate.data_dir()` and `situate data-dir`.
    assert situate_pkg.data_dir() == data
    where = json.loads(situate("data-dir", "--json").stdout)
    assert Path(where["data_dir"]) == data.resolve()
    assert Path(where["examples"]) == (data / "examples").resolve()
    assert situate("--data-dir").stdout.strip() == where["data_dir"]


def test_the_demo_runs_outside_the_checkout_with_the_packages_interpreter(tmp_path: Path) -> None:
    data = _cli.data_dir()
    assert data is not None
    # No python3 on PATH at all: the sequencer must run with the package's own interpreter.
    env = {"HOME": os.environ.get("HOME", str(tmp_path)), "PATH": str(tmp_path / "no-bin")}
    result = subprocess.run(
        [situate_program(), "demo", "--headless", "--json", "--map", str(data / "maps/small.yaml")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    outcome = json.loads(result.stdout.strip().splitlines()[-1])
    assert outcome["sequencer_exit"] == 0, result.stderr[-3000:]
    assert outcome["delivered"] is True


@pytest.mark.skipif(shutil.which("cmake") is None, reason="needs cmake and a C compiler")
def test_a_c_skill_builds_with_the_packages_cmake_and_program_alone(tmp_path: Path) -> None:
    data = _cli.data_dir()
    assert data is not None
    where = json.loads(situate("cmake-dir", "--json").stdout)
    assert Path(where["cmake_dir"]) == (data / "cmake").resolve()
    assert (Path(where["include_dir"]) / "situate.h").is_file()
    assert situate("--cmake-dir").stdout.strip() == where["cmake_dir"]
    # The example, copied out of the package; on PATH only the package's scripts and the system's
    # tools: no situate-gen anywhere, the structs come from `situate gen`.
    source = tmp_path / "runaway"
    shutil.copytree(data / "examples" / "c" / "runaway", source)
    scripts = str(Path(situate_program()).parent)
    env = {**os.environ, "PATH": os.pathsep.join([scripts, "/usr/local/bin", "/usr/bin", "/bin"])}
    env.pop("SITUATE_PROGRAM", None)
    assert shutil.which("situate-gen", path=env["PATH"]) is None
    build = tmp_path / "build"
    configure = subprocess.run(
        ["cmake", "-S", str(source), "-B", str(build), f"-Dsituate_DIR={where['cmake_dir']}"],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=False,
    )
    assert configure.returncode == 0, configure.stdout + configure.stderr
    assert f"situate: C/C++ skill structs by `{situate_program()} -q gen`" in configure.stdout
    built = subprocess.run(
        ["cmake", "--build", str(build)],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=False,
    )
    assert built.returncode == 0, built.stdout + built.stderr
    types = situate("types", "--library", str(build / "libc_runaway.so"), "--json")
    assert types.returncode == 0, types.stderr
    assert "c.runaway" in [t["name"] for t in json.loads(types.stdout)]


@pytest.mark.parametrize(
    ("args", "code", "kind"),
    [
        (["chekc"], 2, "usage"),
        (["skills", "--connect", "tcp/127.0.0.1:{port}", "--timeout", "1"], 4, "no_robot"),
    ],
)
def test_exit_codes_and_json_errors_come_through_the_wheel(
    args: list[str], code: int, kind: str
) -> None:
    port = free_port()
    result = situate(*[a.format(port=port) for a in args], "--json")
    assert result.returncode == code, result.stderr
    error = json.loads(result.stdout)["error"]
    assert (error["kind"], error["exit"]) == (kind, code)


def test_a_bad_robot_file_is_exit_3(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("robot: r\nskills:\n  - {name: w, type: toy.wandr}\n")
    result = situate("check", str(bad))
    assert result.returncode == 3
    assert f"{bad}:3:" in result.stderr


def test_the_sbom_names_local_crates_by_relative_paths(tmp_path: Path) -> None:
    import importlib.util
    import zipfile

    script = Path(__file__).resolve().parents[2] / "scripts" / "sbom_relative.py"
    spec = importlib.util.spec_from_file_location("sbom_relative", script)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    wheel = tmp_path / "x-0.1-py3-none-any.whl"
    sbom = '{"bom-ref": "path+file:///build/here/crates/x#0.1.0", "src": "file:///build/here"}'
    with zipfile.ZipFile(wheel, "w") as z:
        z.writestr("x/__init__.py", "")
        z.writestr("x-0.1.dist-info/sboms/x.cyclonedx.json", sbom)
        z.writestr("x-0.1.dist-info/RECORD", "")
    assert module.rewrite(wheel, "/build/here/") == 1
    with zipfile.ZipFile(wheel) as z:
        text = z.read("x-0.1.dist-info/sboms/x.cyclonedx.json").decode()
        record = z.read("x-0.1.dist-info/RECORD").decode()
    assert "/build/here" not in text
    assert "path+file:crates/x#0.1.0" in text
    assert "x-0.1.dist-info/sboms/x.cyclonedx.json,sha256=" in record


def test_the_published_crates_carry_the_web_app_demo_and_cmake_package() -> None:
    # A published crate cannot reach ../../web/dist or ../../demo: the script copies them in
    # and checks each package's file list (`cargo package --list`, no build).
    if shutil.which("cargo") is None:
        pytest.skip("cargo is not installed here")
    result = subprocess.run(
        ["scripts/publish-crates.sh", "--check"],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "situate_gui:" in result.stdout
    assert "web-dist/index.html" in result.stdout
    assert "data/demo/robot.yaml" in result.stdout
    assert "data/cmake/situateConfig.cmake" in result.stdout

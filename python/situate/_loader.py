"""Imports a robot file's ``python:`` files and collects their ``@situate.skill`` types.

Called by the native loader (``crates/apis/situate_py/src/loader.rs``) for each file
a robot file lists. Each file is imported by path under a module name of its
own (so two files named ``skills.py`` never clash), with its directory on
``sys.path`` so it can import its neighbours. Every problem is a
:class:`SkillLoadError` whose message names the file, and the line when there
is one.
"""

from __future__ import annotations

import importlib.util
import itertools
import re
import sys
import traceback
from pathlib import Path

from .skill import Skill, SkillDeclarationError

__all__ = ["SkillLoadError", "load_file"]

_serial = itertools.count(1)


class SkillLoadError(Exception):
    """A ``python:`` file that cannot be loaded; the message names the file (and line)."""


def _line_in(path: Path, tb: object) -> int | None:
    """The last line of ``path`` in a traceback, if it went through that file."""
    line = None
    for frame in traceback.extract_tb(tb):  # type: ignore[arg-type]
        try:
            same = Path(frame.filename).resolve() == path
        except OSError:
            same = False
        if same:
            line = frame.lineno
    return line


def load_file(path: str) -> list[Skill]:
    """Imports ``path`` and returns the skills found in its namespace (in definition order).

    Raises:
        SkillLoadError: The file is missing, does not import (syntax error,
            exception, bad declaration) or declares no skill.
    """
    file = Path(path)
    if not file.is_file():
        raise SkillLoadError(f"{path}: no such Python file")
    resolved = file.resolve()
    stem = re.sub(r"\W", "_", resolved.stem)
    module_name = f"_situate_py_skills_{stem}_{next(_serial)}"
    spec = importlib.util.spec_from_file_location(module_name, resolved)
    if spec is None or spec.loader is None:
        raise SkillLoadError(f"{path}: cannot be imported as a Python module")
    module = importlib.util.module_from_spec(spec)
    directory = str(resolved.parent)
    if directory not in sys.path:
        sys.path.insert(0, directory)
    sys.modules[module_name] = module
    try:
        spec.loader.exec_module(module)
    except SyntaxError as e:
        sys.modules.pop(module_name, None)
        where = f"{path}:{e.lineno}" if e.lineno else path
        if e.offset:
            where += f":{e.offset}"
        raise SkillLoadError(f"{where}: syntax error: {e.msg}") from None
    except SkillDeclarationError as e:
        sys.modules.pop(module_name, None)
        line = _line_in(resolved, e.__traceback__)
        where = f"{path}:{line}" if line else path
        raise SkillLoadError(f"{where}: {e}") from None
    except Exception as e:
        sys.modules.pop(module_name, None)
        line = _line_in(resolved, e.__traceback__)
        where = f"{path}:{line}" if line else path
        # The traceback from the user's file on: the loader's and importlib's frames above it
        # say nothing about the mistake.
        tb = e.__traceback__
        while tb is not None and Path(tb.tb_frame.f_code.co_filename) != resolved:
            tb = tb.tb_next
        raise SkillLoadError(
            f"{where}: {type(e).__name__} while importing: {e}\n"
            + "".join(traceback.format_exception(type(e), e, tb or e.__traceback__)).rstrip()
        ) from None
    skills: list[Skill] = []
    for value in vars(module).values():
        if isinstance(value, Skill) and all(value is not s for s in skills):
            skills.append(value)
    if not skills:
        raise SkillLoadError(
            f"{path}: declares no skill (decorate a function or a class with @situate.skill(...))"
        )
    seen: dict[str, Skill] = {}
    for s in skills:
        if s.name in seen:
            raise SkillLoadError(f"{path}: two skills are named `{s.name}`")
        seen[s.name] = s
    return skills

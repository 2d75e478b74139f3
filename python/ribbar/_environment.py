"""Where the command line finds gmsh and itself when run from Python."""

from __future__ import annotations

import os
import shutil
import sys
import sysconfig
from pathlib import Path
from typing import Optional


def _scripts_dirs() -> list[Path]:
    dirs = [Path(sysconfig.get_path("scripts")), Path(sys.executable).parent]
    user = sysconfig.get_path("scripts", f"{os.name}_user")
    if user:
        dirs.append(Path(user))
    return dirs


def _installed_script(name: str) -> Optional[Path]:
    for directory in _scripts_dirs():
        candidate = directory / name
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    found = shutil.which(name)
    return Path(found) if found else None


def gmsh_program() -> Optional[Path]:
    """The `gmsh` launcher installed beside this interpreter by the PyPI
    `gmsh` package, else the first `gmsh` on PATH."""
    return _installed_script("gmsh")


def prepare_environment(env: Optional[dict] = None) -> dict:
    """Sets `GMSH` (unless the user set it) and `RIBBAR_EXE` in `env`
    (default: this process's environment) and returns it."""
    env = os.environ if env is None else env
    if not env.get("GMSH"):
        gmsh = gmsh_program()
        if gmsh is not None:
            env["GMSH"] = str(gmsh)
    if not env.get("RIBBAR_EXE"):
        exe = _installed_script("ribbar")
        if exe is not None:
            env["RIBBAR_EXE"] = str(exe)
    return env

"""Rewrites a wheel's CycloneDX SBOMs so that they name local crates by repository-relative paths.

maturin writes ``path+file:///abs/build/dir/crates/x#0.1.0``; this makes it
``path+file:crates/x#0.1.0`` and updates the wheel's RECORD. Usage: ``sbom_relative.py WHEEL ROOT``.
"""

from __future__ import annotations

import base64
import hashlib
import sys
import zipfile
from pathlib import Path


def relativize(text: str, root: str) -> str:
    """Returns ``text`` with ``file://ROOT/`` (and ``file://ROOT``) made relative to ROOT."""
    root = root.rstrip("/")
    return text.replace(f"file://{root}/", "file:").replace(f"file://{root}", "file:.")


def record_line(name: str, data: bytes) -> str:
    """A RECORD line: the file's name, sha256 (urlsafe base64, no padding) and size."""
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def rewrite(wheel: Path, root: str) -> int:
    """Rewrites the wheel in place; returns how many SBOM files changed."""
    with zipfile.ZipFile(wheel) as z:
        items = [(info, z.read(info.filename)) for info in z.infolist()]
    changed = 0
    files: dict[str, bytes] = {}
    for info, data in items:
        if "/sboms/" in info.filename and info.filename.endswith(".json"):
            new = relativize(data.decode(), root).encode()
            changed += new != data
            data = new
        files[info.filename] = data
    record = next(name for name in files if name.endswith(".dist-info/RECORD"))
    lines = [record_line(n, d) for n, d in files.items() if n != record] + [f"{record},,"]
    files[record] = ("\n".join(lines) + "\n").encode()
    tmp = wheel.with_suffix(".tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for info, _ in items:
            z.writestr(info, files[info.filename], zipfile.ZIP_DEFLATED)
    tmp.replace(wheel)
    return changed


if __name__ == "__main__":
    wheel, root = Path(sys.argv[1]), sys.argv[2]
    n = rewrite(wheel, root)
    print(f"sbom_relative.py: {wheel.name}: {n} SBOM file(s) made relative to the repository")

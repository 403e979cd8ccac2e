# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Whether a folder takes a new file, asked before any work; files written whole or not at all."""
from __future__ import annotations

import os
from pathlib import Path
import secrets
import shutil
import tempfile


def folder_writable(folder) -> bool:
    """
    Return whether a new file can be made in ``folder`` (an existing folder).

    The permission bits first, then a file made and removed: root passes every permission
    check, yet a read-only or virtual file system (``/sys``, ``/proc``) still refuses it.
    """
    folder = Path(folder)
    if not os.access(folder, os.W_OK | os.X_OK):
        return False
    try:
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False


def write_file(path, write) -> Path:
    """
    Write ``path`` by ``write(temporary_path)`` beside it, then rename the file into place.

    A write stopped part way (a full disk, Ctrl-C) leaves the file that was there, or none,
    never half of one: a reader of a policy, a model or a JSON record sees it whole or not at
    all. The temporary file takes the mode a new file gets (the umask), or the replaced file's.
    A path that is there and not a regular file (``/dev/null``, a pipe) is written in place, as
    is a file of one's own in a folder that takes no new file; a symbolic link's target is the
    file replaced. The folder is made if missing. An OSError is raised again naming ``path``,
    not the temporary file.
    """
    path = Path(path)
    target = Path(os.path.realpath(path))
    if target.exists() and not target.is_file():
        write(target)
        return path
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        temporary = _new_file(target)
    except OSError as exc:
        if target.is_file() and os.access(target, os.W_OK):
            write(target)                       # the folder refuses a new file; this one is ours
            return path
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
    try:
        if target.exists():
            shutil.copymode(target, temporary)
        write(temporary)
        os.replace(temporary, target)
    except BaseException as exc:
        temporary.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
        raise
    return path


def write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all (:func:`write_file`)."""
    return write_file(path, lambda temporary: temporary.write_text(text, encoding='utf-8'))


def _new_file(target: Path) -> Path:
    """Create an empty, unused hidden file beside ``target``, with the mode the umask gives."""
    while True:
        temporary = target.with_name(f'.{target.name}.{os.getpid()}.'
                                     f'{secrets.token_hex(4)}.tmp')
        try:
            os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        return temporary


def write_figure(fig, path, dpi: int) -> Path:
    """Save a matplotlib figure whole or not at all, in the format its suffix names (PNG)."""
    form = Path(path).suffix.lstrip('.').lower() or 'png'
    return write_file(path, lambda temporary: fig.savefig(temporary, dpi=dpi, format=form))

# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""Whether a folder takes a new file, asked before any work that writes there."""
from __future__ import annotations

import os
from pathlib import Path
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

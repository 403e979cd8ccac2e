# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
The layer contract (``.importlinter``, docs/design.md section 8) holds and catches a breach.

``lint-imports`` (import-linter) reads every import of the package, imports inside functions
included. The contract passes on the tree; a copy of the tree in which a core module imports
``ipomdp_gaze.nodes`` (at the top, or inside a function) fails it, naming the import. The layer
picture in docs/design.md is the contract's own ``layers`` list.
"""
from __future__ import annotations

import configparser
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

from conftest import REPO
import pytest

CONFIG = REPO / '.importlinter'
LINT_IMPORTS = Path(sys.executable).parent / 'lint-imports'


def lint_imports(root: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, 'PYTHONPATH': str(root)}
    return subprocess.run([str(LINT_IMPORTS), '--config', str(CONFIG), '--no-cache'], cwd=root,
                          env=env, capture_output=True, text=True, timeout=300)


def copy_tree(tmp_path: Path) -> Path:
    root = tmp_path / 'src'
    for name in ('ipomdp_gaze', 'policies', 'msg_adapters'):
        shutil.copytree(REPO / name, root / name, symlinks=True,
                        ignore=shutil.ignore_patterns('__pycache__'))
    return root


def test_the_tree_keeps_the_layer_contract():
    out = lint_imports(REPO)
    assert out.returncode == 0, out.stdout + out.stderr
    assert 'Contracts: 2 kept, 0 broken.' in out.stdout


@pytest.mark.parametrize('where', ['top', 'function'])
def test_a_core_module_that_imports_nodes_breaks_the_contract(tmp_path, where):
    root = copy_tree(tmp_path)
    grid = root / 'ipomdp_gaze' / 'model' / 'grid.py'
    text = grid.read_text()
    if where == 'top':
        text += '\nimport ipomdp_gaze.nodes.params  # noqa\n'
    else:
        text += '\n\ndef _sneaky():\n    from ipomdp_gaze.nodes import params  # noqa\n'
    grid.write_text(text)
    out = lint_imports(root)
    assert out.returncode == 1, out.stdout
    assert 'Each layer imports only the layers below it BROKEN' in out.stdout
    assert 'ipomdp_gaze.model.grid -> ipomdp_gaze.nodes.params' in out.stdout


def test_a_new_module_must_be_placed_in_a_layer(tmp_path):
    root = copy_tree(tmp_path)
    (root / 'ipomdp_gaze' / 'unplaced.py').write_text('"""A module no layer names."""\n')
    out = lint_imports(root)
    assert out.returncode == 1
    assert 'ipomdp_gaze.unplaced' in out.stdout


def test_design_md_shows_the_contract_layers():
    parser = configparser.ConfigParser()
    parser.read(CONFIG)
    layers = [line.strip() for line in
              parser['importlinter:contract:layers']['layers'].strip().splitlines()]
    design = (REPO / 'docs' / 'design.md').read_text()
    block = re.search(r'<!-- layers: \.importlinter -->\n```\n(.*?)```', design, re.S)
    assert block, 'docs/design.md has no layers block'
    assert [line.strip() for line in block.group(1).strip().splitlines()] == layers


def test_the_old_flat_names_import_the_moved_modules_with_a_warning():
    code = ('import warnings, importlib\n'
            'warnings.simplefilter("error")\n'
            'from ipomdp_gaze.search import session\n'
            'try:\n'
            '    importlib.import_module("ipomdp_gaze.session")\n'
            'except DeprecationWarning as exc:\n'
            '    print(exc)\n'
            'warnings.simplefilter("ignore")\n'
            'import ipomdp_gaze.session as old, ipomdp_gaze.observation_file as files\n'
            'from ipomdp_gaze.files import observation_file\n'
            'print(old is session, files is observation_file, old.SearchSettings.__module__)\n')
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         timeout=120, cwd=REPO)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == [
        'ipomdp_gaze.session moved to ipomdp_gaze.search.session',
        'True True ipomdp_gaze.search.session']

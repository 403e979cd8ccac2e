# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
I-POMDP infomax model of eye movement: the numpy model core (no rclpy).

The core is grouped by what each module is (docs/design.md section 8): ``model`` (grid, FPOC,
observation, belief, motion, stopping, ...), ``search`` (settings, session, sensors, the
controller's logic), ``simulation`` (simulate, evaluation, gym, executor, progress), ``files``
(observation and YAML files, bags, render) and ``vision``. The flat names of earlier releases
(``ipomdp_gaze.session``, ``ipomdp_gaze.observation_file``, ...) still import, as the same module
objects, with a ``DeprecationWarning`` naming the new path (README, "Changes").
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

# Old flat module name -> where it lives now.
MOVED = {
    **{name: f'model.{name}' for name in (
        'grid', 'fpoc', 'observation', 'belief', 'motion', 'stopping', 'false_alarms', 'checks',
        'still_evidence', 'inhibition', 'head', 'head_camera')},
    **{name: f'search.{name}' for name in (
        'session', 'sensors', 'settings', 'gaze', 'health', 'controller_config', 'answer')},
    **{name: f'simulation.{name}' for name in (
        'simulate', 'evaluation', 'gym', 'executor', 'progress')},
    **{name: f'files.{name}' for name in (
        'observation_file', 'yaml_files', 'bag', 'share_files', 'render')},
    'detection': 'vision.detection', 'replay': 'drivers.replay', 'pieces': 'drivers.pieces',
    'vision.scene_eval': 'drivers.scene_eval', 'nodes.config': 'files.share_files',
    'vision.cell_observation': 'model.cell_observation',
    'nodes.processes': 'harness.processes', 'nodes.watch': 'harness.watch',
    'nodes.demo': 'harness.demo',
}


class _MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Import an old flat module name as the module at its new place (the same object)."""

    def find_spec(self, fullname, path=None, target=None):
        """Return a spec for an old name of this package, else None."""
        prefix = f'{__name__}.'
        if fullname.startswith(prefix) and fullname[len(prefix):] in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        """Import the module at its new place and hand it out under the old name too."""
        new = f'{__name__}.{MOVED[spec.name[len(__name__) + 1:]]}'
        warnings.warn(f'{spec.name} moved to {new}', DeprecationWarning, stacklevel=2)
        return importlib.import_module(new)

    def exec_module(self, module):
        """Nothing to run: the module ran when it was imported at its new place."""


if not any(isinstance(finder, _MovedModules) for finder in sys.meta_path):
    sys.meta_path.append(_MovedModules())

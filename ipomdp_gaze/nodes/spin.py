# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Spin a node until SIGINT or SIGTERM, with a bounded wait so that the signal is never missed.

rclpy's signal handler (a thread of its own) first triggers the executors' signal guard
condition and then shuts the contexts down. An executor that wakes between the two sees its
context still running, consumes the guard condition and waits again; with no timer of its own
(an idle simulated camera) that wait has no timeout, so the process ignores the SIGTERM until it
is killed (``exit status -9`` in the tests). A timer that does nothing bounds every wait to
:data:`WAKE_PERIOD_S`, after which the executor sees the shut-down context and returns.
"""
from __future__ import annotations

import difflib
from pathlib import Path
import re
import sys

from ipomdp_gaze.model.wording import counted
import rclpy
from rclpy.clock import Clock, ClockType
import yaml

WAKE_PERIOD_S = 0.25


def _wake() -> None:
    """Do nothing: the executor only needs to return from its wait."""


def spin(node, wake_period_s: float = WAKE_PERIOD_S) -> None:
    """
    Spin ``node`` until its context shuts down, waking at least every ``wake_period_s``.

    Raises
    ------
    rclpy.executors.ExternalShutdownException
        When a signal shut the context down (as :func:`rclpy.spin` does).

    """
    # On the steady clock: a node's own clock is the simulated one under use_sim_time, and a
    # paused /clock would stop the wake-up, so a signal could wait for the next tick.
    timer = node.create_timer(wake_period_s, _wake, clock=Clock(clock_type=ClockType.STEADY_TIME))
    try:
        rclpy.spin(node)
    finally:
        node.destroy_timer(timer)


def run_node(make_node, node_name: str, args=None) -> int:
    """
    Run a node with the Jazzy idiom: init, spin until SIGINT/SIGTERM, destroy, try_shutdown.

    ROS arguments rcl cannot parse (a missing or malformed ``--params-file``, a ``-p`` without
    ``:=``, an unknown ``--ros-args`` flag) and an argument that is not for ROS print one line
    and return 2, named by the program run (:func:`program_name`). An invalid start-up
    parameter (``ValueError`` or ``ParameterException`` from the node's constructor) prints one
    line naming it and returns 1; a clean shutdown returns 0. Parameters given for the node that
    it does not have (a typo) and a params file with no section for it are warned about
    (:func:`warn_unused_parameters`), since rclpy ignores both silently. Only the constructor's
    errors are configuration errors: an exception that escapes a callback while spinning (a
    callback not guarded by :class:`ipomdp_gaze.nodes.guard.CallbackGuard`) is a bug, and is
    raised with its traceback.
    """
    from rclpy.exceptions import ParameterException
    from rclpy.executors import ExternalShutdownException
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from rclpy.utilities import remove_ros_args
    argv = list(sys.argv if args is None else args)
    program = program_name(argv, node_name)
    try:
        own = remove_ros_args(args=argv)[1:]    # what is not for ROS: the node takes nothing
    except Exception:                           # noqa: B902 (rcl's own parse error, below)
        own = []
    if own:
        if set(own) & {'-h', '--help'}:
            run = program if program.startswith('ipomdp-gaze ') else \
                f'ros2 run ipomdp_gaze {program}'
            print(f'usage: {run} [--ros-args --params-file FILE '
                  f'-p NAME:=VALUE -r FROM:=TO ...]\n\nRun the {node_name} node until Ctrl-C '
                  'or SIGTERM. Its topics, services and parameters: README.md (the "For robot '
                  'users" sections); its shipped parameter files: share/ipomdp_gaze/config/.')
            return 0
        print(f'{program}: error: unexpected argument{"s" * (len(own) > 1)} '
              f'{" ".join(own)} (ROS arguments go after --ros-args; --help for usage)',
              file=sys.stderr)
        return 2
    try:
        rclpy.init(args=args)
    except (_rclpy.RCLError, _rclpy.UnknownROSArgsError) as exc:
        print(f'{program}: error: {ros_args_error(exc)}', file=sys.stderr)
        return 2
    node = None
    status = 0
    try:
        try:
            node = make_node()
        except (ValueError, ParameterException) as exc:
            print(f'{node_name}: error: {exc}', file=sys.stderr)
            status = 1
        else:
            warn_unused_parameters(node, sys.argv if args is None else args)
            spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except _rclpy.RCLError:
        # SIGTERM/SIGINT shut the context down while the executor was building its wait set.
        if rclpy.ok():
            raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


def program_name(argv, node_name: str) -> str:
    """
    Return the name of the program run, for its command-line errors, from ``argv[0]``.

    ``controller`` for ``ros2 run ipomdp_gaze controller`` (``lib/ipomdp_gaze/controller``)
    and ``python -m ipomdp_gaze.nodes.controller`` (``.../controller.py``); the CLI passes
    its command as it was typed (``ipomdp-gaze controller``). Without ``argv[0]``, the node.
    """
    first = str(argv[0]) if argv else ''
    if not first:
        return node_name
    return first if first.startswith('ipomdp-gaze ') else Path(first).stem


def ros_args_error(exc) -> str:
    """
    Return rcl's complaint about the command line in one line, without its C source locations.

    ``failed to initialize rcl: Couldn't parse params file: '--params-file x.yaml'. Error: Error
    opening YAML file, at /project/src/parser.c:271, at ...`` becomes everything before the
    first ``, at /``; an unknown flag (``UnknownROSArgsError``, a list) is named.
    """
    if type(exc).__name__ == 'UnknownROSArgsError':
        flags = re.findall(r"'([^']*)'", str(exc)) or [str(exc)]
        return f"unknown ROS arguments: {' '.join(flags)}"
    text = ' '.join(str(exc).split())
    return re.split(r',? at /', text, maxsplit=1)[0].strip()


def params_file_sections(path) -> list[str]:
    """
    Return the node names a ROS params file has sections for (``/ns/node``, ``/**``, ...).

    Nested namespaces (``ns: {node: {ros__parameters: ...}}``) are joined with ``/``. An
    unreadable file gives an empty list (rcl has already read it, or refused it).
    """
    return [section for section, _ in _file_sections(path)]


def _file_sections(path) -> list[tuple[str, dict]]:
    """Return ``(section, ros__parameters)`` of each section of a params file ([] unreadable)."""
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError, UnicodeDecodeError):
        return []
    out = []

    def walk(node, prefix):
        if not isinstance(node, dict):
            return
        for key, value in node.items():
            name = f'{prefix}/{str(key).strip("/")}'
            if isinstance(value, dict) and 'ros__parameters' in value:
                out.append((name, value['ros__parameters']))
            else:
                walk(value, name)
    walk(data, '')
    return out


def _flat_names(params, prefix: str = '') -> set[str]:
    """Return the parameter names of a ``ros__parameters`` mapping (nested keys joined by .)."""
    if not isinstance(params, dict):
        return set()
    names = set()
    for key, value in params.items():
        name = f'{prefix}{key}'
        names |= _flat_names(value, name + '.') if isinstance(value, dict) else {name}
    return names


def _wildcard_only(argv, own: str) -> set[str]:
    """
    Return the names ``own`` is given only by wildcard sections (``/**``), by no other way.

    rclpy merges every source into one set of overrides; the params files on the command line
    say which came from a section that names no node (shared by every node of a launch), and
    ``-p`` and a section naming the node are its own.
    """
    wildcard, named = set(), set()
    for path in _params_files(argv):
        for section, params in _file_sections(path):
            if _matches(section, own):
                (wildcard if '*' in section else named).update(_flat_names(params))
    argv = [str(a) for a in argv or []]
    named.update(argv[i + 1].split(':=', 1)[0] for i, a in enumerate(argv[:-1])
                 if a in ('-p', '--param'))
    return wildcard - named


def package_parameters() -> set[str]:
    """Return the parameters every node of this package declares (their declaration lists)."""
    from .camera import camera_params
    from .controller import controller_params
    from .detector import detector_params
    from .recorder import recorder_params
    from .scene_camera import scene_camera_params
    return {p.name for make in (camera_params, controller_params, detector_params,
                                recorder_params, scene_camera_params) for p in make()}


def _params_files(argv) -> list[str]:
    """Return the files given with ``--params-file`` in ``argv``."""
    argv = [str(a) for a in argv or []]
    return [argv[i + 1] for i, a in enumerate(argv[:-1]) if a == '--params-file']


def warn_unused_parameters(node, argv) -> list[str]:
    """
    Warn (once each, on the node's logger) about parameters the node was given but does not have.

    rclpy ignores an override for a parameter a node never declares, and a params file whose
    sections name other nodes: a misspelt ``confidance`` or ``gaze_controler:`` would run on
    defaults without a word. Returns the warnings. A parameter of another node of this package
    given only in a wildcard section (``/**:``, a params file shared by a launch's nodes) is
    not warned about: one info line names them all (a typo there, or in the node's own section
    or ``-p``, is still warned about).
    """
    declared = set(node._parameters)           # rclpy has no public view of either
    given = set(getattr(node, '_parameter_overrides', {}))
    own = node.get_fully_qualified_name()
    warnings, shared = [], []
    wildcard = _wildcard_only(argv, own) if given - declared else set()
    others = package_parameters() if wildcard else set()
    for name in sorted(given - declared):
        if name in wildcard and name in others:
            shared.append(name)                 # another node's, in a section shared by all
            continue
        near = difflib.get_close_matches(name, sorted(declared), n=1)
        warnings.append(f"parameter '{name}' is not a parameter of this node; ignored"
                        + (f" (did you mean '{near[0]}'?)" if near else ''))
    for path in _params_files(argv):
        sections = params_file_sections(path)
        if sections and not any(_matches(section, own) for section in sections):
            warnings.append(f'params file {path} has no section for node {own} '
                            f"(its sections: {', '.join(sections)}); none of it applies")
    if shared:
        node.get_logger().info(f"{counted(len(shared), 'parameter')} of other ipomdp_gaze "
                               f"nodes in a wildcard (/**) section, not this node's: "
                               f"{', '.join(shared)}; ignored here")
    for text in warnings:
        node.get_logger().warning(text)
    return warnings


def _matches(section: str, node_name: str) -> bool:
    """Whether a params-file section applies to ``node_name`` (``/ns/node``; ``*`` wildcards)."""
    pattern = re.escape(section).replace(r'/\*\*', '(/.*)?').replace(r'\*', '[^/]*')
    if not section.startswith('/'):
        pattern = '/' + pattern
    return re.fullmatch(pattern, node_name) is not None

# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Detectors by name: the one factory every command, worker and node builds its detector with.

A detector **kind** is one of:

- a name declared in the entry-point group ``ipomdp_gaze.detectors`` (:data:`ENTRY_POINT_GROUP`)
  by any installed distribution, e.g. in its ``setup.py``::

      entry_points={'ipomdp_gaze.detectors': ['blob = my_package.blob:BlobDetector']}

  This package declares ``haar`` (:class:`ipomdp_gaze.vision.detector.HaarDetector`),
  ``yunet`` (:class:`ipomdp_gaze.vision.yunet.YuNetDetector`) and ``ensemble`` (several of
  them as one, :class:`ipomdp_gaze.vision.ensemble.EnsembleDetector`); these are also found in a
  source checkout whose metadata is not installed, and an entry point cannot replace them; a
  name two installed distributions declare with different targets is refused;
- ``package.module:Factory``: the module is imported and ``Factory`` called. **Importing a
  module runs its code**: a kind read from an observation file or a parameter runs whatever that
  module does, so only use files and modules you trust.

``Factory(**options)`` returns the detector (the interface is in
:mod:`ipomdp_gaze.vision.detector`). Its ``settings()`` must return the options it was built
with; the factory records the kind it built the detector by (so a plug-in need not know the
name it was installed under). :func:`detector_from_settings` rebuilds a detector from an
observation file's record: a factory with a ``from_settings(settings, **context)`` class method
with it (the Haar cascade and YuNet check their file's SHA-256 there), any other with
``Factory(**options)``, the options being the settings without ``kind`` and the detector's
``info_keys``. The rebuilt detector's settings must then equal the recorded ones, except the
``info_keys`` (the OpenCV version, the window), which :func:`compare_settings` reports as notes
when they differ.
"""
from __future__ import annotations

from collections.abc import Mapping
import contextlib
import importlib
from importlib import metadata
import inspect
import math
import re

from ipomdp_gaze.files.yaml_files import check_record, RECORD_KINDS
from ipomdp_gaze.vision.detector import (COLORS, detector_settings, INFO_KEYS, KIND_ATTRIBUTE,
                                         OPTIONS_ATTRIBUTE)

ENTRY_POINT_GROUP = 'ipomdp_gaze.detectors'
# The shipped detectors: declared as entry points in setup.py, and found here without them.
BUILTIN = {
    'haar': 'ipomdp_gaze.vision.detector:HaarDetector',
    'yunet': 'ipomdp_gaze.vision.yunet:YuNetDetector',
    'ensemble': 'ipomdp_gaze.vision.ensemble:EnsembleDetector',
}
DEFAULT_KIND = 'haar'
_TARGET = re.compile(r'[A-Za-z_][\w.]*:[A-Za-z_][\w.]*')


def entry_point_kinds() -> dict:
    """Detector names declared in :data:`ENTRY_POINT_GROUP` by installed distributions."""
    return {ep.name: ep for ep in metadata.entry_points(group=ENTRY_POINT_GROUP)}


def _entry_point(kind: str):
    """
    Return the one entry point declaring ``kind``, or None.

    Raises
    ------
    ValueError
        If installed distributions declare the name with different targets: which one loaded
        would depend on the order of ``sys.path``, and a model would be applied with a detector
        it was not calibrated with.

    """
    found = [ep for ep in metadata.entry_points(group=ENTRY_POINT_GROUP) if ep.name == kind]
    targets = sorted({ep.value for ep in found})
    if len(targets) > 1:
        owners = '; '.join(sorted(f'{_owner(ep)}: {ep.value}' for ep in found))
        raise ValueError(f'detector {kind!r} is declared by more than one installed package '
                         f'({owners}); uninstall one, or give package.module:Factory')
    return found[0] if found else None


def _owner(ep) -> str:
    """Name the distribution that declares an entry point (as far as it is known)."""
    dist = getattr(ep, 'dist', None)
    return 'a package' if dist is None else f'{dist.metadata["Name"]} {dist.version}'


def detector_kinds() -> list[str]:
    """Every detector name that can be built: the shipped ones, then the entry points."""
    return list(BUILTIN) + sorted(set(entry_point_kinds()) - set(BUILTIN))


def _import_target(target: str, kind: str):
    module_name, _, attribute = target.partition(':')
    try:
        obj = importlib.import_module(module_name)
    except ImportError as exc:
        raise ValueError(f'detector {kind!r}: cannot import module {module_name!r} ({exc}; '
                         f'is its package installed, or its folder on PYTHONPATH?)') from None
    except Exception as exc:                    # noqa: B902 (a plug-in failing as it loads)
        raise ValueError(f'detector {kind!r}: importing module {module_name!r} failed: '
                         f'{type(exc).__name__}: {exc}') from None
    for part in attribute.split('.'):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise ValueError(f'detector {kind!r}: module {module_name!r} has no '
                             f'{attribute!r}') from None
    return obj


def load_factory(kind: str):
    """
    Return the factory of a detector kind (module docstring): a name or ``module:Factory``.

    Raises
    ------
    ValueError
        For a kind that is neither a known name nor an importable ``module:Factory``; the
        message lists the known names.

    """
    if not isinstance(kind, str) or not kind:
        raise ValueError(f'a detector kind must be a non-empty string, got {kind!r}')
    if kind in BUILTIN:
        factory = _import_target(BUILTIN[kind], kind)
    elif _TARGET.fullmatch(kind):
        factory = _import_target(kind, kind)
    else:
        found = _entry_point(kind)
        if found is None:
            raise ValueError(f'unknown detector {kind!r}; known: {", ".join(detector_kinds())} '
                             f'(or give package.module:Factory)')
        try:
            factory = found.load()
        except (ImportError, AttributeError) as exc:
            raise ValueError(f'detector {kind!r}: its entry point {found.value!r} does not '
                             f'load ({exc})') from None
        except Exception as exc:                # noqa: B902 (a plug-in failing as it loads)
            raise ValueError(f'detector {kind!r}: loading its entry point {found.value!r} '
                             f'failed: {type(exc).__name__}: {exc}') from None
    if not callable(factory):
        raise ValueError(f'detector {kind!r} is not callable: {factory!r}')
    return factory


def _checked(detector, kind: str, options: dict):
    """Check what a factory returned against the interface; record its kind and options."""
    if not callable(detector):
        raise ValueError(f'detector {kind!r}: the factory returned {type(detector).__name__}, '
                         f'which is not callable')
    color = getattr(detector, 'color', 'gray')
    if color not in COLORS:
        raise ValueError(f'detector {kind!r}: color must be one of {", ".join(COLORS)}, got '
                         f'{color!r}')
    window = getattr(detector, 'window_px', None)
    if window is not None and not _is_window(window):
        raise ValueError(f'detector {kind!r}: window_px must be (width, height) in pixels, '
                         f'got {window!r}')
    settings = getattr(detector, 'settings', None)
    if settings is not None:
        if not callable(settings):
            raise ValueError(f'detector {kind!r}: settings must be a method, got {settings!r}')
        if type(detector).__module__.split('.')[0] != 'ipomdp_gaze':
            try:
                answer = settings()
            except Exception as exc:            # noqa: B902 (a plug-in's bug, named)
                raise ValueError(f'detector {kind!r}: its settings() raised '
                                 f'{type(exc).__name__}: {exc}') from None
            if not isinstance(answer, Mapping):
                raise ValueError(f'detector {kind!r}: its settings() must return a dict of '
                                 f'its options, got {type(answer).__name__}')
    try:
        setattr(detector, KIND_ATTRIBUTE, kind)
        setattr(detector, OPTIONS_ATTRIBUTE, dict(options))
    except AttributeError:
        pass                    # a detector with __slots__ records its own kind and options
    return detector


def _is_window(window) -> bool:
    """Whether ``window`` is two finite numbers, a ``window_px`` (width, height)."""
    try:
        return len(window) == 2 and all(math.isfinite(float(side)) for side in window)
    except (TypeError, ValueError):
        return False


def option_names(factory) -> set | None:
    """Return the keyword options a factory takes (None: any, or its signature is unknown)."""
    try:
        parameters = inspect.signature(factory).parameters.values()
    except (TypeError, ValueError):
        return None
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
        return None
    return {p.name for p in parameters
            if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)}


class _BuildFailed(ValueError):
    """A plug-in raised as it was built: the message names it already."""


@contextlib.contextmanager
def _named_errors(kind: str):
    """
    Turn a plug-in's unexpected error as it is built into one line naming it.

    Its TypeError and ValueError are left to the caller, which names the options; the shipped
    detectors' errors (a missing cascade: FileNotFoundError) and running out of memory stay
    what they are.
    """
    try:
        yield
    except (MemoryError, TypeError, ValueError):
        raise
    except Exception as exc:                    # noqa: B902 (whatever a plug-in raises)
        if kind in BUILTIN:
            raise
        raise _BuildFailed(f'detector {kind!r}: building it failed: {type(exc).__name__}: '
                           f'{exc}') from None


def make_detector(kind: str = DEFAULT_KIND, **options):
    """
    Build a detector by kind with its own options, ``Factory(**options)``.

    Raises
    ------
    ValueError
        For an unknown kind, options the factory refuses (its message), or a result that is not
        a detector.

    """
    factory = load_factory(kind)
    known = option_names(factory)
    unknown = sorted(set(options) - known) if known is not None else []
    if unknown:
        raise ValueError(f'detector {kind!r} has no option {", ".join(map(repr, unknown))} '
                         f'(its options: {", ".join(sorted(known)) or "none"})')
    try:
        with _named_errors(kind):
            detector = factory(**options)
    except (TypeError, ValueError) as exc:
        # the shipped factories name the option they refuse; a plug-in's error may not
        if isinstance(exc, _BuildFailed) or (isinstance(exc, ValueError) and kind in BUILTIN):
            raise
        raise ValueError(f'detector {kind!r}: bad options {sorted(options)} ({exc})') from None
    # A factory rebuilt by from_settings records itself whole; one rebuilt as factory(**options)
    # from its record needs its options there (detector_settings keeps those settings() omits).
    return _checked(detector, kind, {} if hasattr(factory, 'from_settings') else options)


def detector_from_spec(spec: dict | None):
    """
    Build a detector from ``{'kind': ..., option: value, ...}`` (no kind: ``haar``).

    This is what calibration workers receive: plain types that cross process boundaries.
    """
    spec = dict(spec or {})
    return make_detector(spec.pop('kind', DEFAULT_KIND), **spec)


def info_keys_of(detector_or_factory) -> tuple:
    """Return the settings a detector records for information only (default :data:`INFO_KEYS`)."""
    return tuple(getattr(detector_or_factory, 'info_keys', INFO_KEYS))


def compare_settings(recorded: dict, current: dict, info_keys=INFO_KEYS) -> list[str]:
    """
    Check a detector's ``current`` settings against the ``recorded`` ones; return notes.

    Raises
    ------
    ValueError
        Naming the first setting (sorted) that differs, other than ``info_keys``.

    Returns
    -------
    list of str
        One note per information-only setting that differs (e.g. another OpenCV version).

    """
    keys = sorted(set(recorded) | set(current))
    for key in keys:
        if key in info_keys:
            continue
        if recorded.get(key) != current.get(key):
            raise ValueError(f'the observation model was measured with detector {key} '
                             f'{recorded.get(key)!r} but the detector has {current.get(key)!r}')
    return [f'the observation model was measured with detector {key} {recorded.get(key)!r}, '
            f'this one has {current.get(key)!r}' for key in keys
            if key in info_keys and key in recorded and recorded.get(key) != current.get(key)]


def takes_cascade_dir(factory) -> bool:
    """Whether a factory's ``from_settings`` takes ``cascade_dir`` (by name or ``**kwargs``)."""
    from_settings = getattr(factory, 'from_settings', None)
    if not callable(from_settings):
        return False
    params = inspect.signature(from_settings).parameters
    return 'cascade_dir' in params or any(p.kind == p.VAR_KEYWORD for p in params.values())


def detector_from_settings(settings: dict, cascade_dir=None, on_note=None):
    """
    Rebuild the detector an observation model records (``meta['detector']``).

    ``cascade_dir`` is passed to factories whose ``from_settings`` takes it (the Haar cascade:
    the folder holding the cascade files). ``on_note(text)``, if given, hears each
    information-only setting that differs (:func:`compare_settings`), e.g. another OpenCV
    version, whose DNN scores may differ in their last digits.

    Raises
    ------
    ValueError
        For an unknown kind, bad settings, or a rebuilt detector whose settings differ from the
        recorded ones (for example another cascade or model file: its SHA-256 differs).
    FileNotFoundError
        If a file the detector needs is not installed.

    """
    if not isinstance(settings, dict) or not settings.get('kind'):
        raise ValueError(f'detector settings must be a mapping with a kind, got {settings!r}')
    check_detector_record(settings)
    kind = settings['kind']
    factory = load_factory(kind)
    info = info_keys_of(factory)
    from_settings = getattr(factory, 'from_settings', None)
    if callable(from_settings):
        takes = takes_cascade_dir(factory)
        context = {'cascade_dir': cascade_dir} if cascade_dir is not None and takes else {}
        with _named_errors(kind):
            detector = from_settings(dict(settings), **context)
        options = {}                            # its settings() gives what it was built with
    else:
        options = {k: v for k, v in settings.items() if k != 'kind' and k not in info}
        try:
            with _named_errors(kind):
                detector = factory(**options)
        except TypeError as exc:
            raise ValueError(f'detector {kind!r} cannot be rebuilt from {sorted(options)} '
                             f'({exc})') from None
    detector = _checked(detector, kind, options)
    for note in compare_settings(settings, detector_settings(detector), info_keys_of(detector)):
        if on_note is not None:
            on_note(note)
    return detector


def declared_types(factory) -> dict:
    """
    Return the ``record_types`` a detector's factory declares, or ``{}``.

    Only a mapping of names to kinds of :data:`~ipomdp_gaze.files.yaml_files.RECORD_KINDS` (a
    trailing ``?``: null too) is a declaration: a plug-in's own attribute of that name that is
    something else says nothing of its record (it was a KeyError in the check).
    """
    types = getattr(factory, 'record_types', None)
    if isinstance(types, dict) and all(
            isinstance(k, str) and isinstance(v, str) and v.rstrip('?') in RECORD_KINDS
            for k, v in types.items()):
        return types
    return {}


def check_detector_record(settings, at: str = 'detector') -> dict:
    """
    Check the YAML types of a detector's record (an observation file's ``detector``).

    Every key is text, ``kind`` a detector kind, and each key its factory declares in
    ``record_types`` (the shipped detectors do) of its type; an ensemble's members each a
    detector's record with an integer ``weight``, none an ensemble (a YAML alias can make an
    ensemble its own member: checking it was a RecursionError). A hand-edited record was a
    ``TypeError`` from the detector's ``float()`` or ``list()``, naming neither the key nor
    the file.

    Raises
    ------
    ValueError
        ``{at}.{key} must be {what}, got {value}``.

    """
    check_record(settings, {'kind': 'text'}, at)
    if not settings.get('kind'):
        raise ValueError(f'{at}.kind is missing (the detector kind, e.g. haar)')
    factory = load_factory(settings['kind'])
    check_record(settings, declared_types(factory), at)
    if settings['kind'] == 'ensemble':
        for i, member in enumerate(settings.get('members') or []):
            where = f'{at}.members[{i}]'
            check_record(member, {'weight': 'integer', 'kind': 'text'}, where)
            if member.get('kind') == settings['kind']:
                raise ValueError(f'{where}: an ensemble cannot hold an ensemble')
            check_detector_record({k: v for k, v in member.items() if k != 'weight'}, where)
    return settings


def parse_options(pairs) -> dict:
    """
    Read ``name=value`` strings into detector options; values are YAML scalars.

    ``['score_threshold=0.5', 'model=my.onnx']`` gives ``{'score_threshold': 0.5,
    'model': 'my.onnx'}``.

    Raises
    ------
    ValueError
        For a string without ``=`` or with an empty name.

    """
    import yaml
    options = {}
    for pair in pairs or ():
        name, sep, text = str(pair).partition('=')
        name = name.strip()
        if not sep or not name:
            raise ValueError(f'a detector option must be NAME=VALUE, got {pair!r}')
        try:
            value = yaml.safe_load(text) if text.strip() else ''
        except yaml.YAMLError:
            value = text
        options[name] = value
    return options

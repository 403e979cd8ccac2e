# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
What every versioned YAML file of the package shares: reading, the header checks, plain types.

Policy files (``ipomdp_gaze/policy-v1``) and observation files (``ipomdp_gaze/observation-v1``)
are mappings with a ``format`` string, required and allowed keys, and free-form records; both
are read with ``yaml.safe_load`` only and report the first problem in one line through their own
``ValueError`` subclass (docs/design.md section 9).
"""
from __future__ import annotations

from pathlib import Path

from ipomdp_gaze.files.writable import write_text
from ipomdp_gaze.model.checks import is_number, short_repr
import numpy as np
import yaml


class DuplicateKeyError(yaml.YAMLError):
    """A mapping gives one key twice (PyYAML would keep the last silently)."""

    def __init__(self, key, mark):
        super().__init__(f'the key {key!r} appears twice')
        self.key, self.problem_mark = key, mark


class UniqueKeyLoader(yaml.SafeLoader):
    """The safe loader, refusing a key given twice in one mapping (a hand edit appended)."""


def _unique_mapping(loader, node, deep=False):
    seen = set()
    for key_node, _ in node.value:
        if key_node.tag == 'tag:yaml.org,2002:merge':
            continue
        key = loader.construct_object(key_node, deep=True)
        try:
            duplicate = key in seen
        except TypeError:
            continue                            # unhashable: construct_mapping says so
        if duplicate:
            raise DuplicateKeyError(key, key_node.start_mark)
        seen.add(key)
    return loader.construct_mapping(node, deep=deep)


UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _unique_mapping)

if getattr(yaml, '__with_libyaml__', False):
    class UniqueKeyCLoader(yaml.CSafeLoader):
        """:class:`UniqueKeyLoader` on libyaml's parser (the same constructors, 5-10x faster)."""

    UniqueKeyCLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
                                     _unique_mapping)
else:                                           # pragma: no cover - PyYAML without libyaml
    UniqueKeyCLoader = None


def _load(text: str, loader_class):
    loader = loader_class(text)                 # what yaml.safe_load does, with the key check
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def in_folder(path, folder) -> bool:
    """Whether ``path`` is a file directly in ``folder`` (the package's models or kernels)."""
    try:
        return Path(path).resolve().parent == Path(folder).resolve()
    except OSError:
        return False


def read_yaml(path: Path, error: type[ValueError], shipped: bool = False):
    """
    Parse a YAML file with the safe loader (a key given twice in one mapping refused).

    ``shipped``: a file the package ships (its models and kernels), parsed by libyaml, 5-10x
    faster (``find`` read its two models and the kernels in about 2 s of its 3). libyaml
    reads a few odd inputs otherwise than PyYAML's own parser (a tab after a value, a bare
    ``!``, a byte-order mark inside the text), so a user's file is always read by the latter,
    and so is a shipped file that libyaml cannot read.

    Raises
    ------
    error
        ``<path>: cannot read``, ``<path>: not YAML at line N``, ``<path>: the key 'k'
        appears twice (line N)`` or nested too deeply.

    """
    try:
        text = Path(path).read_text(encoding='utf-8')
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f'{path}: cannot read: {exc}') from None
    if shipped and UniqueKeyCLoader is not None:
        try:
            return _load(text, UniqueKeyCLoader)
        except (yaml.YAMLError, RecursionError):
            pass                                # the Python parser words the problem
    try:
        return _load(text, UniqueKeyLoader)
    except DuplicateKeyError as exc:
        raise error(f'{path}: {exc} (line {exc.problem_mark.line + 1}): which one is meant? '
                    'keep one') from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f' at line {mark.line + 1}' if mark is not None else ''
        raise error(f'{path}: not YAML{where}') from None
    except RecursionError:
        raise error(f'{path}: YAML nested too deeply to read') from None


def yaml_kind(doc) -> str:
    """Name what a YAML document is in the words of YAML, not Python's (``NoneType``)."""
    if doc is None:
        return 'nothing (an empty document)'
    if isinstance(doc, bool):
        return 'true or false'
    if isinstance(doc, (int, float)):
        return f'the number {doc!r}'
    if isinstance(doc, str):
        return 'one line of text' if '\n' not in doc else 'text'
    return {list: 'a list'}.get(type(doc), f'a {type(doc).__name__}')


def _integer(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def _list_of(test, value, length=None) -> bool:
    """Tell a list (a tuple, from code rather than YAML) of items passing ``test``."""
    return isinstance(value, (list, tuple)) and all(test(v) for v in value) and (
        length is None or len(value) == length)


# The types a record's keys may be declared to have (check_record): a test and its words.
RECORD_KINDS = {
    'text': (lambda v: isinstance(v, str), 'text'),
    'texts': (lambda v: isinstance(v, str) or (_list_of(lambda x: isinstance(x, str), v)
                                               and bool(v)), 'text or a list of text'),
    'number': (is_number, 'a number'),
    'integer': (_integer, 'an integer'),
    'flag': (lambda v: isinstance(v, bool), 'true or false'),
    'flags': (lambda v: isinstance(v, bool) or _list_of(lambda x: isinstance(x, bool), v),
              'true, false or a list of them'),
    'size': (lambda v: _integer(v) or _list_of(_integer, v, 2),
             'an integer or a [width, height] pair of integers'),
    'pair': (lambda v: _list_of(_integer, v, 2), 'a [width, height] pair of integers'),
    'integers': (lambda v: _list_of(_integer, v), 'a list of integers'),
    'numbers': (lambda v: _list_of(is_number, v), 'a list of numbers'),
    'matrix3x3': (lambda v: _list_of(is_number, v, 9), '9 numbers (a 3x3 matrix, row-major)'),
    'mapping': (lambda v: isinstance(v, dict), 'a mapping'),
    'mappings': (lambda v: _list_of(lambda x: isinstance(x, dict), v) and bool(v),
                 'a non-empty list of mappings'),
}


def check_record(record, types: dict, at: str) -> dict:
    """
    Check the YAML types of a record of a file (``detector``, ``fovea``): one line if wrong.

    ``types`` maps a key to a kind of :data:`RECORD_KINDS` (a trailing ``?``: null too); other
    keys are left to the record's reader, but every key must be text. A hand-edited record
    reached its reader's ``float()`` or ``sorted()``, whose ``TypeError`` named neither the
    file nor the key. Returns ``record``.

    Raises
    ------
    ValueError
        ``{at}.{key} must be {what}, got {value}`` (or ``{at} must be a mapping``).

    """
    if not isinstance(record, dict):
        raise ValueError(f'{at} must be a mapping, got {yaml_kind(record)}')
    for key, value in record.items():
        if not isinstance(key, str):
            raise ValueError(f'{at} must map names (text) to values, got the key '
                             f'{short_repr(key)}')
        kind = types.get(key)
        if kind is None or (kind.endswith('?') and value is None):
            continue
        test, words = RECORD_KINDS[kind.rstrip('?')]
        if not test(value):
            null = ' (or null)' if kind.endswith('?') else ''
            raise ValueError(f'{at}.{key} must be {words}{null}, got {short_repr(value)}')
    return record


def check_header(doc, what: str, fmt: str, required, keys, error: type[ValueError]) -> None:
    """
    Check a document is a mapping with every required key, no unknown key and the format string.

    Raises
    ------
    error
        Naming the first problem.

    """
    if not isinstance(doc, dict):
        raise error(f'{what} must be a YAML mapping, got {yaml_kind(doc)}')
    for key in required:
        if key not in doc:
            raise error(f'missing key {key}')
    unknown = sorted(str(k) for k in set(doc) - set(keys))
    if unknown:
        raise error(f"unknown key {unknown[0]}; valid: {', '.join(keys)}")
    if doc['format'] != fmt:
        raise error(f"wrong format string {doc['format']!r}; expected {fmt!r}")


def plain(value):
    """Convert numpy scalars and arrays (nested in dicts and lists) to plain Python types."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


def write_yaml(path, doc: dict) -> Path:
    """Write ``doc`` (plain types) as block YAML, keys in order, whole or not at all."""
    path = Path(path)
    write_text(path, yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=100))
    return path


def flatten(tree: dict, prefix: str = '') -> dict:
    """Nested YAML parameters -> dotted names (``{'grid': {'rows': 11}}`` -> ``grid.rows``)."""
    out = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            out.update(flatten(value, name + '.'))
        else:
            out[name] = value
    return out


def yaml_parameters(path, node_name: str) -> dict:
    """
    Read the ``ros__parameters`` of ``node_name`` from a parameter file, dotted names.

    The node's section is ``/**/node_name:`` (the shipped files: it applies in any namespace),
    ``/node_name:`` or ``node_name:``.
    """
    tree = yaml.safe_load(Path(path).read_text())
    for key in (f'/**/{node_name}', f'/{node_name}', node_name):
        try:
            return flatten(tree[key]['ros__parameters'])
        except (KeyError, TypeError):
            continue
    raise ValueError(f'{path} has no /**/{node_name}: ros__parameters block')

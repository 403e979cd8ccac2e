# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Build a policy from a name, a kernel or a policy file: the one place that does it.

The controller node, the ``evaluate`` and ``search`` commands and the benches call
:func:`build_policy`; a kernel is checked once (by :class:`ipomdp_gaze.policies.conv.ConvPolicy`),
a policy file once (by :mod:`ipomdp_gaze.policies.policy_file`).
"""
from __future__ import annotations

from .baselines import make_baseline, STRATEGIES
from .conv import check_action, ConvPolicy

POLICY_NAMES = ('learned',) + STRATEGIES + ('nmpt',)
# Policies built from a name alone (no kernel or file): what the CLI's --policy takes.
NAMED_POLICIES = POLICY_NAMES[1:]


class PolicyUnavailable(ValueError):
    """A policy that cannot be built here: a policy file or module that does not exist."""


def build_policy(name: str, grid, model, kernel=None, file: str = '', action: str | None = None,
                 warn=None, scene: dict | None = None):
    """
    Build the policy called ``name`` (one of :data:`POLICY_NAMES`).

    ``model`` is the task's observation model (or an FPOC, for the Gaussian model). ``nmpt`` is
    NMPT's fixed policy (:class:`ipomdp_gaze.policies.nmpt.NMPTPolicy`; it always samples).
    ``learned`` uses ``kernel`` (a convolutional kernel, 2-D or row-major) when it is non-empty,
    else the policy ``file`` (a policy YAML path or a shipped kernel name); ``action``
    (``argmax`` or ``sample``) applies to it (None: the file's own rule; a kernel: argmax). A
    file trained on another FPOC, or (given ``scene``, :func:`.policy_file.check_scene`) on
    other scenes, is accepted and ``warn(message)`` is called; one for another grid is refused.

    Raises
    ------
    PolicyUnavailable
        If the policy file does not exist (neither a path nor a shipped kernel name) or a policy
        module is missing from this install.
    ValueError
        For an unknown name, a bad kernel or a policy file that is invalid or does not fit the
        grid (:class:`ipomdp_gaze.policies.policy_file.PolicyFileError` is a ValueError).

    """
    if action is not None:
        check_action(action)
    if name in STRATEGIES:
        try:
            return make_baseline(name, grid, model)
        except ImportError as exc:
            raise PolicyUnavailable(f'policy {name!r} is not available in this install '
                                    f'({exc})') from None
    if name == 'nmpt':
        from .nmpt import NMPTPolicy
        return NMPTPolicy(grid)
    if name != 'learned':
        raise ValueError(f"unknown policy {name!r}; valid policies: {', '.join(POLICY_NAMES)}")
    if kernel is not None and len(kernel):
        return ConvPolicy(grid, kernel, action=action or 'argmax', what='policy.kernel')
    if not file:
        raise ValueError("policy 'learned' needs policy.kernel or policy.file")
    try:
        from .policy_file import load_policy, PolicyFileError, resolve_source
    except ImportError as exc:
        raise PolicyUnavailable(f'policy files are not supported by this install ({exc})') \
            from None
    try:
        resolve_source(file)
    except PolicyFileError as exc:
        raise PolicyUnavailable(str(exc)) from None
    return load_policy(file, grid=grid, fpoc=model, action=action, warn=warn, scene=scene)

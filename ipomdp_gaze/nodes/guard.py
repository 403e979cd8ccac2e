# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
No callback can end a node: every subscription, timer and service callback runs guarded.

rclpy lets an exception raised in a callback escape ``rclpy.spin``, which ends the node (and
:func:`ipomdp_gaze.nodes.spin.run_node` used to report it as a bad start-up parameter). A node
registers each callback through :meth:`CallbackGuard.wrap`; an exception the callback did not
expect is then counted with its reason (per callback, and the last one in full), logged as a
throttled warning, and the node carries on with the next message. Only start-up configuration
errors end a node.

The counts are in ``/diagnostics``: merged into the node's own status (:meth:`values`), or, for
a node without one, in a status of their own, ``<node>: callbacks`` (:meth:`publish_status`):
OK while ``callback_errors`` is 0, WARN after an error.

The guarded callbacks of a node also run one at a time under the guard's lock, and so do its
parameter sets and ``destroy_node`` (:class:`GuardedNode`). In its own process a node is spun
by one thread; composed in one process and spun by a ``MultiThreadedExecutor``, its callbacks
are still one mutually exclusive group, but another node's callback may call ``set_parameters``
on it, or unload it, while one of them is under way.
"""
from __future__ import annotations

from collections import Counter
import contextlib
import functools
import threading

WARN_THROTTLE_S = 5.0
DIAGNOSTICS_PERIOD_S = 1.0
# Exceptions that mean "stop the process", never swallowed.
_PASS_THROUGH = (KeyboardInterrupt, SystemExit)


def _service_response(args: tuple):
    """
    Return the response of a service callback's ``(request, response)``, else None.

    A response is a ROS message; another callback of two arguments (a parameter transaction's
    ``apply(old, new)``) is not a service: its failure returned ``new`` as if it were one, and
    the node logged the whole configuration after ``parameters set:``.
    """
    if len(args) == 2 and hasattr(type(args[1]), 'get_fields_and_field_types'):
        return args[1]
    return None


def _shutdown_exceptions() -> tuple:
    from rclpy.executors import ExternalShutdownException
    return _PASS_THROUGH + (ExternalShutdownException,)


class CallbackGuard:
    """
    Wrap a node's callbacks so that an unexpected exception is counted, logged and survived.

    Parameters
    ----------
    node : rclpy.node.Node
        The node whose logger reports the errors.

    """

    def __init__(self, node):
        self.node = node
        self.errors = 0
        self.by_callback: Counter = Counter()
        self.last_error = ''
        self._pass_through = _shutdown_exceptions()
        self._status_pub = None
        self.lock = threading.RLock()   # one guarded callback, parameter set or destroy at a time
        self.closed = False             # destroy_node has run: later callbacks do nothing

    def _shutting_down(self) -> bool:
        """Return whether the node's context is shut down (nothing can be published)."""
        context = getattr(self.node, 'context', None)
        try:
            return context is not None and not context.ok()
        except Exception:  # noqa: B902 (a context torn down under us is shut down too)
            return True

    def record(self, name: str, exc: BaseException) -> str:
        """Count an exception raised in callback ``name``; return its one-line reason."""
        reason = f'{type(exc).__name__}: {exc}'.replace('\n', ' ')[:300]
        self.errors += 1
        self.by_callback[name] += 1
        self.last_error = f'{name}: {reason}'
        self.node.get_logger().warning(
            f'callback {name} failed ({self.errors} so far), carrying on: {reason}',
            throttle_duration_sec=WARN_THROTTLE_S)
        return reason

    def wrap(self, callback, name: str | None = None):
        """
        Return ``callback`` guarded: what it raises is counted and it returns None instead.

        A service callback (called with ``request, response``) returns the response it was
        given, with ``success = False`` and the reason as ``message`` when it has those fields.
        It runs under :attr:`lock`; once the node is destroyed it does nothing (a message taken
        before ``destroy_node`` would be published on destroyed publishers).
        """
        name = name or getattr(callback, '__name__', 'callback').lstrip('_')

        @functools.wraps(callback)
        def guarded(*args):
            with self.lock:
                if self.closed:
                    return _service_response(args)
                return self._call(callback, name, args)
        return guarded

    def _call(self, callback, name: str, args: tuple):
        """Call ``callback(*args)``: what it raises is counted (see :meth:`wrap`)."""
        try:
            return callback(*args)
        except self._pass_through:
            raise
        except Exception as exc:  # noqa: B902 (that is the point of the guard)
            if self._shutting_down():
                return None         # Ctrl-C while a callback ran: its publish has no context
            reason = self.record(name, exc)
            response = _service_response(args)
            if response is not None:                # a service: (request, response)
                if hasattr(response, 'success'):
                    response.success = False
                if hasattr(response, 'message'):
                    response.message = f'internal error: {reason}'
                return response
            return None

    def refusing(self, build, name: str = 'parameters'):
        """
        Return ``build`` with an unexpected exception turned into a ``ValueError`` (counted).

        For a parameter callback: a ``ValueError`` refuses the change with its reason; anything
        else would end the node inside the set-parameters service.
        """
        pass_through = self._pass_through

        @functools.wraps(build)
        def guarded(*args, **kwargs):
            try:
                return build(*args, **kwargs)
            except (ValueError, *pass_through):
                raise
            except Exception as exc:  # noqa: B902
                raise ValueError(f'internal error: {self.record(name, exc)}') from None
        return guarded

    def values(self) -> dict:
        """``callback_errors``, ``last_callback_error`` and one count per failed callback."""
        out = {'callback_errors': self.errors, 'last_callback_error': self.last_error}
        out.update({f'callback_errors.{k}': v for k, v in sorted(self.by_callback.items())})
        return out

    def publish_status(self, period_s: float = DIAGNOSTICS_PERIOD_S, publisher=None) -> None:
        """
        Publish ``<node>: callbacks`` on ``/diagnostics`` every ``period_s`` from now on.

        ``publisher``: the node's own ``/diagnostics`` publisher (``DiagnosticArray``, depth 10)
        to send it with; by default one is made. Every publisher costs each wait of the node's
        executor the time of its QoS event handlers, so a node that has one passes it.
        """
        if publisher is None:
            from diagnostic_msgs.msg import DiagnosticArray
            publisher = self.node.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._status_pub = publisher
        self.node.create_timer(period_s, self.wrap(self._publish, 'diagnostics'))

    def _publish(self) -> None:
        from ipomdp_gaze.msg_adapters import diagnostics
        level, message = ('warn', f'{self.errors} callback errors: {self.last_error}') \
            if self.errors else ('ok', 'no callback errors')
        self._status_pub.publish(diagnostics.diagnostic_array(
            [diagnostics.status(f'{self.node.get_fully_qualified_name()}: callbacks', level,
                                message, self.values())],
            self.node.get_clock().now().to_msg()))


class GuardedNode:
    """
    Mixin before ``rclpy.node.Node``: parameter sets and ``destroy_node`` take the guard's lock.

    A ``set_parameters`` called by another node's callback (composed nodes, a multi-threaded
    executor) would otherwise rebuild the search under an evidence callback, and a
    ``destroy_node`` would destroy the publishers a callback is about to use. Both wait for
    the callback under way; callbacks taken before ``destroy_node`` then do nothing.
    """

    def _guard_lock(self):
        guard = getattr(self, 'guard', None)   # None while Node.__init__ runs (one thread)
        return contextlib.nullcontext() if guard is None else guard.lock

    def set_parameters(self, parameter_list):
        """Set parameters as ``Node.set_parameters`` does, between two callbacks."""
        with self._guard_lock():
            return super().set_parameters(parameter_list)

    def set_parameters_atomically(self, parameter_list):
        """Set parameters as ``Node.set_parameters_atomically`` does, between two callbacks."""
        with self._guard_lock():
            return super().set_parameters_atomically(parameter_list)

    def destroy_node(self):
        """Destroy the node once the callback under way has returned; later ones do nothing."""
        with self._guard_lock():
            guard = getattr(self, 'guard', None)
            if guard is not None:
                guard.closed = True
            return super().destroy_node()

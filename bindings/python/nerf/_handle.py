"""Lifetime of C handles, progress callbacks and per-handle log hooks.

libnerf does not reference-count: a renderer must not outlive its model and
sampler, nor a trainer its model, dataset and sampler.  Python frees objects
in any order (and, for garbage in reference cycles, calls finalisers in an
arbitrary order), so the binding does the counting:

* every C handle is owned by a :class:`_Resource` that knows its
  dependencies and counts its users (dependent handles, calls in progress
  and arrays borrowing its memory);
* ``close()`` marks a handle closed at once (any later method call raises
  ``ValueError``), but the C object is destroyed only when nothing uses it
  any more.  So ``model.close()`` while a renderer of that model exists
  defers the real ``nerf_model_destroy`` until the renderer is gone; the
  renderer keeps working meanwhile.

The same happens when the garbage collector, rather than ``close()``,
finalises the Python objects, whatever the order.
"""

from __future__ import annotations

import ctypes
import os
import signal
import threading
import weakref
from typing import Any, Callable, Iterable, List, Optional

from . import errors
from ._capi import PROGRESS_CB, lib
from .structs import LOG_CB, Hooks, Progress

# Re-entrant: a finaliser run by the garbage collector may need the lock
# on a thread that already holds it.
_LOCK = threading.RLock()


class _Resource:
    """One C object: destroyed once closed and no longer used."""

    __slots__ = ("kind", "ptr", "closed", "users", "deps", "keep",
                 "_destroy", "__weakref__")

    def __init__(self, kind: str, ptr: Any, destroy: Callable[[Any], None],
                 deps: Iterable["_Resource"] = (), keep: Any = None) -> None:
        self.kind = kind
        self.ptr = ptr
        self.closed = False
        self.users = 0
        self.deps: List[_Resource] = []
        # Objects the C side points into (callback thunks, hooks); they die
        # with the C object, never before it.
        self.keep = keep
        self._destroy = destroy
        with _LOCK:
            for dep in deps:
                dep.users += 1
                self.deps.append(dep)

    def acquire(self) -> Any:
        """Count one more user and return the C pointer.

        Raises:
            ValueError: the handle was closed.
        """
        with _LOCK:
            if self.closed or self.ptr is None:
                raise ValueError("%s is closed" % self.kind)
            self.users += 1
            return self.ptr

    def release(self) -> None:
        """Drop one user; destroy the C object if it was the last one."""
        with _LOCK:
            self.users -= 1
            self._free_if_unused()

    def close(self) -> None:
        """Mark closed; destroy the C object now or when its users go."""
        with _LOCK:
            self.closed = True
            self._free_if_unused()

    def _free_if_unused(self) -> None:
        if not self.closed or self.users > 0 or self.ptr is None:
            return
        ptr, self.ptr = self.ptr, None
        self._destroy(ptr)
        self.keep = None
        deps, self.deps = self.deps, []
        for dep in deps:
            dep.release()


class _Using:
    """Context manager holding a user count on a resource during a call."""

    __slots__ = ("_res",)

    def __init__(self, res: _Resource) -> None:
        self._res = res

    def __enter__(self) -> Any:
        return self._res.acquire()

    def __exit__(self, *exc: Any) -> None:
        self._res.release()


class Handle:
    """Base of the Python wrappers of C handles.

    Each wrapper has ``close()`` (idempotent) and works as a context
    manager.  Wrappers hold strong references to the wrappers they depend
    on, so a renderer keeps its model and sampler reachable.
    """

    _kind = "handle"

    def __init__(self, res: _Resource) -> None:
        self._res = res
        # Runs res.close() when this wrapper is collected (or at exit); it
        # references the resource only, never the wrapper.
        self._finalizer = weakref.finalize(self, res.close)

    def close(self) -> None:
        """Release the handle.  Safe to call more than once.

        The C object is destroyed at once unless a dependent handle or a
        call in another thread still uses it; then it is destroyed when the
        last of them is done.
        """
        self._finalizer()

    @property
    def closed(self) -> bool:
        """True once :meth:`close` has been called."""
        return self._res.closed

    def _using(self) -> _Using:
        return _Using(self._res)

    def __enter__(self):
        if self._res.closed:
            raise ValueError("%s is closed" % self._kind)
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._res.closed else "open"
        return "<nerf.%s %s at %#x>" % (type(self).__name__, state, id(self))


class ProgressSlot:
    """The progress callback of one renderer or trainer.

    The C callback (a ``CFUNCTYPE`` thunk) is installed once, when the
    handle is created, and stays installed: it is kept in the handle's
    resource so it lives as long as the C object.  It reaches this slot
    through a weak reference only, so a Python callback that refers to its
    own renderer does not keep it alive forever.

    A Python callback returns a true value to cancel.  If it raises, the
    exception (even KeyboardInterrupt) is stored, the thunk returns 1 so
    the C call stops with ``NERF_ECANCELLED``, and :meth:`run` re-raises
    the stored exception instead of :class:`nerf.NerfCancelled`.

    Ctrl-C needs more care: Python raises KeyboardInterrupt at the first
    instruction of whatever Python code runs next, which is the thunk's own
    entry, outside any ``try`` (ctypes would then print "Exception ignored"
    and return garbage to C).  So while a call runs on the main thread with
    Python's default SIGINT handler, :meth:`run` swaps in a handler that
    only records the interrupt; the thunk then cancels the call and
    :meth:`run` raises KeyboardInterrupt once C has returned.  Ctrl-C thus
    stops a long render or training run after the current chunk or step,
    with or without a Python callback.

    :meth:`run` also enforces the C rule "one call at a time per handle":
    a second call, from another thread or from the handle's own progress
    callback, raises RuntimeError instead of corrupting the C object.
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._running = False
        self._interrupted = False
        self.callback: Optional[Callable[[Progress], Any]] = None
        self._override: Optional[Callable[[Progress], Any]] = None
        self._pending: Optional[BaseException] = None
        ref = weakref.ref(self)

        def thunk(p, user):
            slot = ref()
            if slot is None:
                return 0
            return slot._on_progress(p)

        self.thunk = PROGRESS_CB(thunk)

    def _on_progress(self, p) -> int:
        if self._interrupted:
            return 1
        cb = self._override or self.callback
        if cb is None:
            return 0
        try:
            return 1 if cb(Progress.from_struct(p.contents)) else 0
        except BaseException as exc:  # must not cross the C frame
            if self._pending is None:
                self._pending = exc
            return 1

    def run(self, fn: Callable[..., Any], *args: Any,
            progress: Optional[Callable[[Progress], Any]] = None) -> Any:
        """Call ``fn(*args)``, with ``progress`` replacing the slot's
        callback for this call, and re-raise what a callback raised."""
        with _LOCK:
            if self._running:
                raise RuntimeError(
                    "%s is busy: a call is already running on it (from "
                    "another thread, or this is its own progress callback); "
                    "use one %s per thread" % (self.kind, self.kind))
            self._running = True
        self._pending = None
        self._interrupted = False
        self._override = progress
        own_sigint = self._catch_sigint()
        try:
            result = fn(*args)
        except errors.NerfCancelled:
            pending = self._take_pending()
            if pending is not None:
                raise pending from None
            raise
        finally:
            if own_sigint:
                signal.signal(signal.SIGINT, signal.default_int_handler)
            self._override = None
            self._running = False
        pending = self._take_pending()
        if pending is not None:
            raise pending
        return result

    def _catch_sigint(self) -> bool:
        """Record SIGINT instead of raising, if this is the main thread and
        SIGINT has Python's default handler.  Returns whether it did."""
        if threading.current_thread() is not threading.main_thread():
            return False
        if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
            return False

        def record(signum, frame):
            self._interrupted = True

        signal.signal(signal.SIGINT, record)
        return True

    def _take_pending(self) -> Optional[BaseException]:
        """The exception to raise after a call: the callback's, else
        KeyboardInterrupt if Ctrl-C arrived during the call."""
        pending, self._pending = self._pending, None
        if pending is None and self._interrupted:
            pending = KeyboardInterrupt()
        self._interrupted = False
        return pending


def make_hooks(log: Optional[Callable[[int, str], Any]],
               log_level: Optional[int]) -> Optional[tuple]:
    """Hooks routing a handle's log lines to ``log(level, message)``.

    Returns ``(hooks, keep)``, or None when ``log`` is None (the handle then
    uses the process default handler).  ``keep`` must live as long as the
    C object.  An exception raised by ``log`` cannot stop the library's
    work; ctypes reports it (sys.unraisablehook) and the call goes on.
    """
    if log is None:
        if log_level is not None:
            raise ValueError("log_level needs a log callback")
        return None
    if not callable(log):
        raise TypeError("log must be callable as log(level, message)")

    def thunk(level, msg, user):
        log(int(level), msg.decode("utf-8", "replace") if msg else "")

    cfunc = LOG_CB(thunk)
    hooks = Hooks()
    hooks.log_cb = cfunc
    if log_level is not None:
        hooks.log_level = int(log_level)
    return hooks, (hooks, cfunc)


def fspath(path: Any, name: str = "path") -> bytes:
    """A path argument as bytes for C: every path the binding passes to the
    library comes through here.

    Raises:
        TypeError: ``path`` is not a str, bytes or os.PathLike.
        ValueError: ``path`` holds a NUL character, where C would cut it
            short (as Python's own open() refuses it).
    """
    try:
        raw = os.fsencode(path)
    except TypeError:
        raise TypeError("%s: expected a str, bytes or os.PathLike path, "
                        "not %s" % (name, type(path).__name__)) from None
    if b"\0" in raw:
        raise ValueError("%s: embedded null character in %r" % (name, path))
    return raw


def create(kind: str, ptr_type: Any, create_fn: Callable[..., Any],
           destroy: Callable[[Any], None], *args: Any,
           deps: Iterable[_Resource] = (), keep: Any = None) -> _Resource:
    """Call ``create_fn(&out, *args)`` and wrap ``out`` in a resource that
    depends on ``deps``.  The caller holds the dependencies (``_using``)
    while this runs, so none can be destroyed half-way."""
    out = ptr_type()
    create_fn(ctypes.byref(out), *args)
    return _Resource(kind, out, destroy, deps, keep)


def destroyer(name: str) -> Callable[[Any], None]:
    """The library's destroy function ``name``, bound now so that it is
    still reachable when finalisers run at interpreter exit."""
    return getattr(lib, name)


class ProgressHandle(Handle):
    """A handle whose long calls report progress through a ProgressSlot
    (``self._slot``, set by the subclass): renderers and trainers."""

    _slot: "ProgressSlot"

    @property
    def progress(self) -> Optional[Callable[..., Any]]:
        """The progress callback of later long calls (None: none)."""
        return self._slot.callback

    @progress.setter
    def progress(self, callback: Optional[Callable[..., Any]]) -> None:
        if callback is not None and not callable(callback):
            raise TypeError("progress must be callable or None")
        self._slot.callback = callback

"""Stop signals (SIGINT, SIGTERM: Ctrl-C, a scheduler's polite stop) held back while a study's
trial changes hands (:func:`held_stops`), so that a stop never finds a trial asked but not in
hand, or out of hand but not told."""

from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["STOPS", "held_stops", "swap_handlers"]

STOPS = (signal.SIGINT, signal.SIGTERM)


def swap_handlers(handlers: dict) -> dict:
    """Set the stop signals' handlers at once (both blocked meanwhile where signals can be
    masked: a stop between the two swaps is delivered after them, to the new handler);
    returns the previous ones (None, a handler set outside Python, as the default)."""
    masked = hasattr(signal, "pthread_sigmask")
    if masked:
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, STOPS)
    try:
        previous = {sig: signal.signal(sig, handler) for sig, handler in handlers.items()}
    finally:
        if masked:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    return {sig: signal.SIG_DFL if h is None else h for sig, h in previous.items()}


@contextlib.contextmanager
def held_stops():
    """SIGINT and SIGTERM (a polite stop: Ctrl-C, a scheduler) held back while a trial changes
    hands (asked and put in hand, or taken out of hand and told), then raised again for the
    handlers they had: a stop then finds every trial of this coordinator either in hand (put
    back in the queue) or finished, never RUNNING and forgotten. (Handlers, masked only while
    they are swapped: worker processes started meanwhile must not inherit blocked signals.)
    Off the main thread, where handlers cannot be set, nothing is held."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = swap_handlers({sig: lambda signum, _: caught.append(signum) for sig in STOPS})
    try:
        yield
    finally:
        swap_handlers(previous)
        if caught:
            signal.raise_signal(caught[0])

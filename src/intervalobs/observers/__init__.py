"""Observers, one module per family, all on the protocol of :mod:`intervalobs.observers.base`."""

from .base import Observer, ObserverState
from .interval_observer import IntervalObserver
from .unknown_input import UnknownInputIntervalObserver
from .zonotopic import IntegratedObserver, ZonotopicObserver

__all__ = [
    "IntegratedObserver",
    "IntervalObserver",
    "Observer",
    "ObserverState",
    "UnknownInputIntervalObserver",
    "ZonotopicObserver",
]

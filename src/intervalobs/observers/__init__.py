"""Observers, one module per family, all on the protocol of :mod:`intervalobs.observers.base`."""

from .base import Observer, ObserverState
from .hgio import HighGainIntervalObserver
from .interval_observer import IntervalObserver
from .unknown_input import UnknownInputIntervalObserver
from .zonotopic import IntegratedObserver, ZonotopicObserver

__all__ = [
    "HighGainIntervalObserver",
    "IntegratedObserver",
    "IntervalObserver",
    "Observer",
    "ObserverState",
    "UnknownInputIntervalObserver",
    "ZonotopicObserver",
]

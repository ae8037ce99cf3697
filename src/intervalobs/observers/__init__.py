"""Observers, one module per family, all on the protocol of :mod:`intervalobs.observers.base`."""

from .base import Observer, ObserverState
from .interval_observer import IntervalObserver

__all__ = ["IntervalObserver", "Observer", "ObserverState"]

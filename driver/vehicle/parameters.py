"""The vehicle's parameter glue: the table read (from the per-vehicle cache first, off the caller's thread), a value
written only within ArduPilot's documented bounds, and the metadata that says them.

The protocol itself is :mod:`driver.params` (download, FTP, set and echo); this part wires it to the vehicle's
link, state and cache.
"""
from __future__ import annotations

import threading
from concurrent.futures import Future

from ..core.ports import Ports
from ..params.cache import ParameterCache
from ..params.manager import ParameterManager, param_name
from ..params.metadata import metadata_for, set_problem
from .state import CommandStatus, Severity

__all__ = ["Parameters"]


class Parameters:
    """``Vehicle.fetch_parameters``, ``set_parameter`` and ``parameter_metadata`` do their work here, over the
    vehicle's :class:`~driver.params.manager.ParameterManager` (``params``)."""

    def __init__(self, config, ports: Ports, params: ParameterManager):
        self.config = cfg = config
        self._store, self._lock, self._params = ports.state, ports.state.lock, params
        self._outbox, self._answer = ports.outbox, ports.commands.answer
        self._clock, self._replaying = ports.clock, ports.replaying
        self._param_cache = ParameterCache(cfg.param_cache or None) if cfg.param_cache is not None else None
        self._params.on_complete = self.cache
        self._metadata_warned = False         # the metadata is read by start() in the background (half a second)
        self._metadata_error_told = False

    def fetch(self, refresh: bool = False) -> Future:
        """Download every parameter into ``state().parameters`` (driver.params.download)."""
        if self._replaying:
            return self._answer("parameters", CommandStatus.REJECTED, "replaying a recording: no vehicle to ask")
        if refresh or self._param_cache is None:
            with self._lock:
                future = self._params.fetch(refresh, self._clock(), None)
            self._outbox.wake()
            return future
        outer: Future = Future()

        def with_cache() -> None:             # the cache is a file: read here, never on the caller's (UI) thread
            s = self._store.state
            cached = self._param_cache.load(s.system_id, s.firmware)
            with self._lock:
                inner = self._params.fetch(refresh, self._clock(), cached)
            self._outbox.wake()
            inner.add_done_callback(lambda f: outer.set_result(f.result()))
        threading.Thread(target=with_cache, name="param-cache-read", daemon=True).start()
        return outer

    def cache(self, table) -> None:
        """A complete table: kept per vehicle for its next connection (written off the reader's lock)."""
        if self._param_cache is not None:
            s = self._store.view()
            threading.Thread(target=self._param_cache.save, args=(s["system_id"], s["firmware"], table),
                             name="param-cache", daemon=True).start()

    def set(self, name: str, value: float, allow_out_of_bounds: bool = False) -> Future:
        """PARAM_SET in the parameter's own type, confirmed by the vehicle's echo (driver.params.setter); outside
        ArduPilot's documented bounds only when ``allow_out_of_bounds`` (driver.params.metadata)."""
        name = name.upper() if isinstance(name, str) else ""
        if not name or len(name) > 16 or not name.isascii():
            return self._answer(f"param {name}", CommandStatus.REJECTED, "a parameter name is 1 to 16 ASCII characters")
        if self._replaying:
            return self._answer(f"param {name}", CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        metadata = self.metadata(wait=False)      # the caller's (the window's) thread never waits for it
        with self._lock:
            problem = self._params.value_problem(name, float(value))
        problem = problem or set_problem(metadata, name, float(value), allow_out_of_bounds)
        if problem:
            return self._answer(f"param {name}", CommandStatus.REJECTED, problem)
        if metadata is None and not self._metadata_warned:
            self._metadata_warned = True
            self._store.add_message(Severity.WARNING, "No parameter metadata (ArduPilot's apm.pdef.xml): values are "
                                    "written without checking their bounds")
        with self._lock:
            future = self._params.set(name, float(value), self._clock())
        self._outbox.wake()
        return future

    # -- what the vehicle says (reader thread, lock held) ------------------------------------------------------
    def on_param_value(self, m) -> None:
        """A PARAM_VALUE of the autopilot (its value finite: the reader checked it)."""
        self._params.on_param_value(m, param_name(m), self._clock())
        if self._params.reasking:
            self._outbox.wake()                       # the next read goes out now, not on the next tick

    def on_ftp(self, m) -> None:
        """A FILE_TRANSFER_PROTOCOL message addressed to us: the parameters' file (driver.params.ftp)."""
        self._params.on_ftp(m, self._clock())

    def metadata(self, wait: bool = True):
        """The metadata (driver.params.metadata.metadata_for); None when there is none or, without ``wait``,
        while it is still being read. Why it could not be read is told once."""
        outcome = metadata_for(self.config.param_metadata, wait)
        if outcome is None:
            return None
        metadata, error = outcome
        if error:
            with self._lock:
                tell, self._metadata_error_told = not self._metadata_error_told, True
            if tell:
                self._store.add_message(Severity.WARNING, f"Parameter metadata not read: {error}")
        return metadata

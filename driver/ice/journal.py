"""The pilot's messages and command results as a remote drone shows them: the server's, renumbered in one sequence
with the client's own lines, and kept in order across a lost server that comes back (restarted or not).

The server numbers its messages and results from 1; the client asks it only for what came after the last ones it
holds. After a loss it asks for everything again: a restarted server numbers from 1 again, so its messages are
told apart by their time, and its results are numbered after every result shown so far (a window pairs a
command's answer with the result of the same number, which must never be reused).
"""
from __future__ import annotations

import collections
import logging
import time
from dataclasses import replace

from ..vehicle.state import CommandResult, CommandStatus, Message, Severity
from . import convert

log = logging.getLogger("driver.ice.client")

__all__ = ["Journal"]

MAX_MESSAGES = 200
MAX_RESULTS = 50


class Journal:
    """Not thread-safe: the client's lock guards it."""

    def __init__(self) -> None:
        self.messages: collections.deque[Message] = collections.deque(maxlen=MAX_MESSAGES)
        self.results: collections.deque[CommandResult] = collections.deque(maxlen=MAX_RESULTS)
        self.server_message = -1                 # the server's last message and result we hold: asked from there
        self.server_result = -1
        self._line = 0                           # our numbering of messages (the server's and our own)
        self._newest_line_time = 0.0             # the newest server message's time: after a loss, what is new
        self._results_before_restart = 0         # added to the server's result numbers (since it may restart)
        self._highest_result = 0                 # the highest result number shown so far
        self._after_loss = False                 # the server was lost: its numbering may have started again

    def note(self, severity: Severity, text: str) -> None:
        """A line of our own for the pilot."""
        self._line += 1
        self.messages.append(Message(self._line, time.time(), severity, text, "driver"))
        (log.warning if severity <= Severity.WARNING else log.info)("%s", text)

    def take(self, status) -> None:
        """The server's status: its new messages and results, numbered as ours."""
        after_loss, self._after_loss = self._after_loss, False
        for m in status.messages:
            if not after_loss and m.index <= self.server_message:
                continue                         # polled, then published as well (or the other way)
            if not after_loss or m.time > self._newest_line_time:    # after a loss its clock says what is new
                self._line += 1
                self.messages.append(replace(convert.message_from_status(m), index=self._line))
                self._newest_line_time = max(self._newest_line_time, m.time)
        if status.messages:
            self.server_message = max(self.server_message, status.messages[-1].index)
        if after_loss:                           # a restarted server numbers from 1 again
            self._results_before_restart = self._highest_result
        for r in status.results if not after_loss else ():
            if r.index <= self.server_result:
                continue
            result = self.result(r)
            self._highest_result = max(self._highest_result, result.index)
            self.results.append(result)
        if status.results:
            self.server_result = max(self.server_result, status.results[-1].index)

    def result(self, outcome) -> CommandResult:
        """The server's outcome, numbered as in our results (the window pairs a Future's answer with it)."""
        result = convert.result_from_outcome(outcome)
        return replace(result, index=result.index + self._results_before_restart) if result.index > 0 else result

    def own_result(self, name: str, status: CommandStatus, reason: str) -> CommandResult:
        """A result of our own, numbered in our results so the window shows it once."""
        self._highest_result += 1
        result = CommandResult(name, status, reason, 0, self._highest_result)
        self.results.append(result)
        return result

    def server_lost(self) -> None:
        """Ask for everything again when it answers: it may have restarted, numbering from 1."""
        self.server_message = self.server_result = -1
        self._after_loss = True

"""An Ice exception in the pilot's words: one short line, not Ice's multi-line dump.

Its own small module so that the server, the registry, the publisher and the lab all use it without importing
each other.
"""
from __future__ import annotations

import os

import Ice

__all__ = ["ice_problem"]


def ice_problem(exc: Exception) -> str:
    """An Ice exception in a few words on one line ("address already in use"), not Ice's multi-line dump."""
    if isinstance(exc, Ice.DNSException):
        return f"cannot resolve host {exc.host}"
    if isinstance(exc, Ice.FileException) and exc.path:
        return f"{exc.path}: {os.strerror(exc.error).lower() if exc.error > 0 else 'cannot read'}"
    if isinstance(exc, Ice.SyscallException) and exc.error > 0:
        return os.strerror(exc.error).lower()
    text = getattr(exc, "str", "") or getattr(exc, "reason", "") or str(exc)
    return " ".join(str(text).split())

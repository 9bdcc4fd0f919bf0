"""Flight logs reviewed without Qt: a DataFlash .BIN indexed once and read field by field (``dataflash.py``), a
.tlog read into the same shape (``tlog.py``), and what a reviewer asks of either (``log.py``: events, modes,
path, parameters, CSV); a survey's photos geotagged from its camera events (``geotag.py``)."""
from .log import FlightLog, LogError, open_log

__all__ = ["FlightLog", "LogError", "open_log"]

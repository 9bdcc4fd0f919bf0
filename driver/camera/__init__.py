"""Video for the viewer and the server, without Qt: sources, the simulated camera, recording.

``open_source(uri)`` gives a :class:`VideoSource` whose capture thread keeps only the
newest :class:`Frame` (RGB). See ``docs/camera.md`` for the URIs.
"""
from .record import VideoRecorder, dated_path, save_snapshot
from .source import Frame, OpenCVSource, SourceStatus, VideoSource
from .uri import CameraSet, describe_uri, open_source

__all__ = ["Frame", "SourceStatus", "VideoSource", "OpenCVSource", "open_source", "describe_uri", "CameraSet",
           "VideoRecorder", "save_snapshot", "dated_path"]

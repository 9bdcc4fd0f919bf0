"""Video for the viewer and the server, without Qt: sources, the simulated camera, recording.

``open_source(uri)`` gives a :class:`VideoSource` whose capture thread keeps only the
newest :class:`Frame` (RGB). See ``docs/camera.md`` for the URIs.
"""
import os

# OpenCV logs a warning on every failed open or read timeout, which a source retrying for a missing
# camera repeats forever; the sources report those failures themselves. The user's setting wins.
os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")

from .record import VideoRecorder, dated_path, save_snapshot  # noqa: E402  (cv2 reads the level on import)
from .source import Frame, OpenCVSource, SourceStatus, VideoSource  # noqa: E402
from .uri import CameraSet, describe_uri, open_source  # noqa: E402

__all__ = ["Frame", "SourceStatus", "VideoSource", "OpenCVSource", "open_source", "describe_uri", "CameraSet",
           "VideoRecorder", "save_snapshot", "dated_path"]

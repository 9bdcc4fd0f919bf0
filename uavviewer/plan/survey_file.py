"""A survey in a QGroundControl ``.plan``: written as QGroundControl's complex item (``"complexItemType":
"survey"``, its polygon, angle and CameraCalc, its waypoints in TransectStyleComplexItem.Items), and read back as
a survey, editable again (no Qt).

A survey read back becomes a :class:`SurveySpec` only when its settings make here the very waypoints the file
carries: the vehicle must fly what the file says. One made by another planner (QGroundControl's turnarounds,
its own pass spacing) stays its waypoints, and the pilot is told why.
"""
from __future__ import annotations

from driver.mission.files import ComplexItem, PlanFile
from driver.mission.plan import PlanKind

from .survey import CAMERAS, Camera, SurveySpec, survey

__all__ = ["complex_items", "mission_entries"]

SURVEY = "survey"


def _settings(spec: SurveySpec) -> dict:
    c = spec.camera
    width, height = c.footprint(spec.altitude)
    return {
        "version": 5, "angle": spec.angle, "entryLocation": 0, "flyAlternateTransects": False,
        "splitConcavePolygons": False, "polygon": [[lat, lon] for lat, lon in spec.polygon],
        "TransectStyleComplexItem": {
            "version": 1, "CameraTriggerInTurnAround": False, "HoverAndCapture": False, "Refly90Degrees": False,
            "TurnAroundDistance": 0, "FollowTerrain": False,
            "CameraCalc": {
                "version": 1, "CameraName": c.name, "SensorWidth": c.sensor_width, "SensorHeight": c.sensor_height,
                "ImageWidth": c.image_width, "ImageHeight": c.image_height, "FocalLength": c.focal_length,
                "Landscape": c.landscape, "FixedOrientation": False, "ValueSetIsDistance": False,
                "DistanceToSurface": spec.altitude, "DistanceToSurfaceRelative": True,
                "FrontalOverlap": round(spec.front_overlap * 100, 3), "SideOverlap": round(spec.side_overlap * 100, 3),
                "AdjustedFootprintSide": width * (1 - spec.side_overlap),
                "AdjustedFootprintFrontal": height * (1 - spec.front_overlap),
            },
        },
    }


def complex_items(doc) -> tuple[ComplexItem, ...]:
    """Where each survey of ``doc`` (a PlanDocument) stands among the mission's items, with its settings."""
    out, start = [], 0
    for entry in doc.entries:
        if isinstance(entry, SurveySpec):
            count = len(doc.survey_of(entry).items)
            out.append(ComplexItem(start, count, SURVEY, _settings(entry)))
            start += count
        else:
            start += 1
    return tuple(out)


def _spec(settings: dict) -> SurveySpec | None:
    try:
        calc = settings["TransectStyleComplexItem"]["CameraCalc"]
        name = str(calc.get("CameraName", ""))
        camera = next((c for c in CAMERAS if c.name == name), None) or Camera(
            name or "Camera from the file", float(calc["SensorWidth"]), float(calc["SensorHeight"]),
            int(calc["ImageWidth"]), int(calc["ImageHeight"]), float(calc["FocalLength"]),
            bool(calc.get("Landscape", True)))
        spec = SurveySpec(tuple((float(lat), float(lon)) for lat, lon in settings["polygon"]),
                          float(calc["DistanceToSurface"]), camera, float(calc["FrontalOverlap"]) / 100,
                          float(calc["SideOverlap"]) / 100, float(settings.get("angle", 0.0)))
    except (KeyError, TypeError, ValueError):
        return None
    return spec if spec.valid() else None


def mission_entries(got: PlanFile) -> tuple[list, list[str]]:
    """The mission of ``got`` as the editor's entries (surveys where the file has ours), and what was said of
    the complex items kept as waypoints."""
    mission = got.plan(PlanKind.MISSION)
    items = list(mission.items) if mission is not None else []
    groups = {c.start: c for c in got.complex_items}
    entries, notes, i = [], [], 0
    while i < len(items):
        group = groups.get(i)
        spec = _spec(group.settings) if group is not None and group.kind == SURVEY else None
        if spec is not None and tuple(survey(spec).items) == tuple(items[i:i + group.count]):
            entries.append(spec)
            i += group.count
            continue
        if group is not None:
            why = ("its settings make other passes here" if group.kind == SURVEY else
                   "this planner edits surveys only")
            notes.append(f"the {group.kind or 'complex item'} at item {i + 1} is opened as its {group.count} "
                         f"items ({why}); saved from here it is those items")
            entries += items[i:i + group.count]
            i += group.count
            continue
        entries.append(items[i])
        i += 1
    return entries, notes

"""Gamepads through SDL2 (pysdl2, with the SDL2 library of the pysdl2-dll wheel), read on a thread of their own.

SDL's joysticks and its event queue belong to the whole process, so there is one :class:`GamepadReader` per
process (:func:`shared_reader`), shared by every window. It opens every joystick SDL sees, as a *game
controller* when SDL's database knows its layout (Xbox, PlayStation, Switch, many more: the sticks are then
``leftx``/``lefty``/``rightx``/``righty`` whatever the make), otherwise as a raw joystick (``axis0``,
``button0``, ``hat0up``...). It follows hot-plug and hands its listeners immutable :class:`GamepadFrame`
snapshots: at once when a button, a device or a resting stick changes, at most every ``min_interval`` while a
stick keeps moving (the driver sends each change on the wire), and at least every :data:`HEARTBEAT` while a pad
is open, so a listener can tell a stalled reader from a still stick.

No Qt here. :class:`VirtualPad` is SDL's virtual joystick: a real SDL device without hardware, for the tests,
the benches and trying the mapping page.
"""
from __future__ import annotations

import ctypes
import logging
import threading
import time
import warnings
from dataclasses import dataclass
from typing import Callable

__all__ = ["Pad", "PadReading", "GamepadFrame", "GamepadReader", "VirtualPad", "shared_reader", "sdl_problem",
           "HEARTBEAT"]

log = logging.getLogger(__name__)

HEARTBEAT = 0.1           # s: the longest a listener waits for a frame while a pad is open
IDLE_PERIOD = 0.05        # s between polls with no pad: only hot-plug to notice
MIN_INTERVAL = 0.02       # s: a moving stick gives at most 50 frames per second

try:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # pysdl2 says which SDL2 binaries it took
        import sdl2
    _IMPORT_ERROR = ""
except Exception as exc:                          # noqa: BLE001 - no SDL2: the viewer flies without gamepads
    sdl2 = None
    _IMPORT_ERROR = f"SDL2 is not available ({exc})"

_SUBSYSTEMS = 0 if sdl2 is None else sdl2.SDL_INIT_JOYSTICK | sdl2.SDL_INIT_GAMECONTROLLER


def sdl_problem() -> str:
    """Why gamepads cannot be read here ("" when they can)."""
    return _IMPORT_ERROR


def _hints() -> None:
    # SDL must leave Ctrl+C to the viewer, and read pads without a window of its own (we keep focus ourselves).
    sdl2.SDL_SetHint(sdl2.SDL_HINT_NO_SIGNAL_HANDLERS, b"1")
    sdl2.SDL_SetHint(sdl2.SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, b"1")


def _guid_text(guid) -> str:
    buf = ctypes.create_string_buffer(33)
    sdl2.SDL_JoystickGetGUIDString(guid, buf, 33)
    return buf.value.decode("ascii")


@dataclass(frozen=True)
class Pad:
    """One connected controller. ``controller``: SDL's database knows its layout (standard names)."""
    guid: str
    name: str
    instance: int
    controller: bool
    axes: tuple[str, ...]
    buttons: tuple[str, ...]


@dataclass(frozen=True)
class PadReading:
    """A pad's sticks and buttons at one moment. Axes in [-1, 1] (triggers 0..1); a game controller's
    ``lefty``/``righty`` are + when pushed up. ``pressed``: buttons pressed since the last frame, so a tap
    shorter than a frame is never lost."""
    pad: Pad
    axes: tuple[float, ...]
    held: frozenset = frozenset()
    pressed: tuple[str, ...] = ()

    def axis(self, name: str) -> float:
        try:
            return self.axes[self.pad.axes.index(name)]
        except ValueError:
            return 0.0


@dataclass(frozen=True)
class GamepadFrame:
    """Everything the reader knows at ``time`` (monotonic): every open pad, and what came and went."""
    time: float
    readings: tuple[PadReading, ...] = ()
    added: tuple[Pad, ...] = ()
    removed: tuple[Pad, ...] = ()
    error: str = ""

    @property
    def pads(self) -> tuple[Pad, ...]:
        return tuple(r.pad for r in self.readings)


class _Open:
    """A pad the reader holds open (reader thread only)."""

    def __init__(self, index: int) -> None:
        self.controller = bool(sdl2.SDL_IsGameController(index))
        if self.controller:
            self.game_controller = sdl2.SDL_GameControllerOpen(index)
            if not self.game_controller:
                raise OSError(sdl2.SDL_GetError().decode(errors="replace"))
            self.joystick = sdl2.SDL_GameControllerGetJoystick(self.game_controller)
            axes = [a for a in range(sdl2.SDL_CONTROLLER_AXIS_MAX)
                    if sdl2.SDL_GameControllerHasAxis(self.game_controller, a)]
            buttons = [b for b in range(sdl2.SDL_CONTROLLER_BUTTON_MAX)
                       if sdl2.SDL_GameControllerHasButton(self.game_controller, b)]
            self._axes = axes
            self._buttons = buttons
            axis_names = tuple(sdl2.SDL_GameControllerGetStringForAxis(a).decode() for a in axes)
            button_names = tuple(sdl2.SDL_GameControllerGetStringForButton(b).decode() for b in buttons)
            name = sdl2.SDL_GameControllerName(self.game_controller)
        else:
            self.game_controller = None
            self.joystick = sdl2.SDL_JoystickOpen(index)
            if not self.joystick:
                raise OSError(sdl2.SDL_GetError().decode(errors="replace"))
            self._axes = list(range(sdl2.SDL_JoystickNumAxes(self.joystick)))
            self._buttons = list(range(sdl2.SDL_JoystickNumButtons(self.joystick)))
            self._hats = sdl2.SDL_JoystickNumHats(self.joystick)
            axis_names = tuple(f"axis{a}" for a in self._axes)
            button_names = tuple(f"button{b}" for b in self._buttons) + tuple(
                f"hat{h}{d}" for h in range(self._hats) for d in ("up", "down", "left", "right"))
            name = sdl2.SDL_JoystickName(self.joystick)
        self._flip = tuple(n in ("lefty", "righty") for n in axis_names)     # up = +
        self.pad = Pad(guid=_guid_text(sdl2.SDL_JoystickGetGUID(self.joystick)),
                       name=(name or b"").decode(errors="replace") or "Gamepad",
                       instance=sdl2.SDL_JoystickInstanceID(self.joystick), controller=self.controller,
                       axes=axis_names, buttons=button_names)
        self.pressed: list[str] = []
        self.last: tuple | None = None           # (axes, held) last published

    def read(self) -> tuple[tuple[float, ...], frozenset]:
        if self.controller:
            raw = [sdl2.SDL_GameControllerGetAxis(self.game_controller, a) for a in self._axes]
            held = {n for b, n in zip(self._buttons, self.pad.buttons)
                    if sdl2.SDL_GameControllerGetButton(self.game_controller, b)}
        else:
            raw = [sdl2.SDL_JoystickGetAxis(self.joystick, a) for a in self._axes]
            held = {f"button{b}" for b in self._buttons if sdl2.SDL_JoystickGetButton(self.joystick, b)}
            for h in range(self._hats):
                held |= {f"hat{h}{d}" for d in _hat_directions(sdl2.SDL_JoystickGetHat(self.joystick, h))}
        axes = tuple(max(-1.0, min(1.0, (-v if flip else v) / 32767.0)) for v, flip in zip(raw, self._flip))
        return axes, frozenset(held)

    def button_name(self, button: int) -> str:
        if self.controller:
            return sdl2.SDL_GameControllerGetStringForButton(button).decode()
        return f"button{button}"

    def close(self) -> None:
        if self.game_controller:
            sdl2.SDL_GameControllerClose(self.game_controller)
        elif self.joystick:
            sdl2.SDL_JoystickClose(self.joystick)
        self.game_controller = self.joystick = None


def _hat_directions(value: int) -> list[str]:
    return [d for d, bit in (("up", sdl2.SDL_HAT_UP), ("down", sdl2.SDL_HAT_DOWN), ("left", sdl2.SDL_HAT_LEFT),
                             ("right", sdl2.SDL_HAT_RIGHT)) if value & bit]


class GamepadReader:
    """SDL's joysticks on a thread: every pad, hot-plug, frames to the listeners (called on that thread)."""

    def __init__(self, min_interval: float = MIN_INTERVAL) -> None:
        self.min_interval = min_interval
        self._listeners: list[Callable[[GamepadFrame], None]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error = sdl_problem()

    # -- listeners ------------------------------------------------------------------------------
    def subscribe(self, listener: Callable[[GamepadFrame], None]) -> None:
        """Start reading with the first listener; the next frame lists every pad."""
        with self._lock:
            self._listeners.append(listener)
            start = self._thread is None
            if start:
                self._stop = threading.Event()   # each thread its own: one that outlived a join never resumes
                thread = self._thread = threading.Thread(target=self._run, args=(self._stop,), name="gamepads",
                                                         daemon=True)
        if start:
            thread.start()

    def unsubscribe(self, listener: Callable[[GamepadFrame], None]) -> None:
        """Stop reading (and close SDL's joysticks) when the last listener leaves."""
        with self._lock:
            if listener in self._listeners:
                self._listeners.remove(listener)
            thread = self._thread if not self._listeners else None
            if thread is not None:
                self._thread = None
                self._stop.set()
        if thread is not None and thread is not threading.current_thread():
            thread.join(2.0)

    def _publish(self, frame: GamepadFrame) -> None:
        with self._lock:
            listeners = list(self._listeners)
        for listener in listeners:
            try:
                listener(frame)
            except Exception:                    # noqa: BLE001 - one listener must not stop the others
                log.exception("gamepad listener failed")

    # -- the thread -----------------------------------------------------------------------------
    def _run(self, stop: threading.Event) -> None:
        if sdl2 is None:
            self._publish(GamepadFrame(time.monotonic(), error=self.error))
            return
        _hints()
        if sdl2.SDL_InitSubSystem(_SUBSYSTEMS) != 0:
            self.error = f"SDL could not read joysticks: {sdl2.SDL_GetError().decode(errors='replace')}"
            log.warning("%s", self.error)
            self._publish(GamepadFrame(time.monotonic(), error=self.error))
            return
        pads: dict[int, _Open] = {}
        try:
            self._loop(pads, stop)
        except Exception:                        # noqa: BLE001
            log.exception("the gamepad reader failed")
        finally:
            for p in pads.values():
                p.close()
            sdl2.SDL_QuitSubSystem(_SUBSYSTEMS)

    @staticmethod
    def _open(pads: dict[int, _Open], index: int, added: list[Pad]) -> None:
        if sdl2.SDL_JoystickGetDeviceInstanceID(index) in pads:
            return
        try:
            p = _Open(index)
        except OSError as exc:
            log.warning("cannot open joystick %d: %s", index, exc)
            return
        pads[p.pad.instance] = p
        added.append(p.pad)
        log.info("gamepad connected: %s (%s, %s)", p.pad.name, p.pad.guid,
                 "game controller" if p.controller else "joystick")

    def _loop(self, pads: dict[int, _Open], stop: threading.Event) -> None:
        ev = sdl2.SDL_Event()
        added: list[Pad] = []
        removed: list[Pad] = []
        for i in range(sdl2.SDL_NumJoysticks()):         # those already there (their ADDED may be long gone)
            self._open(pads, i, added)
        last_publish = -1e9
        first = True
        coalescing = False                               # a stick moved since the last frame, which is not due
        while not stop.is_set():
            got = self._wait(stop, ev, pads, coalescing, last_publish)
            while got:
                self._event(ev, pads, added, removed)
                got = sdl2.SDL_PollEvent(ctypes.byref(ev))
            now = time.monotonic()
            readings, changed, urgent = [], False, bool(added or removed or first)
            for p in pads.values():
                axes, held = p.read()
                if (axes, held) != p.last:
                    changed = True
                    urgent = urgent or held != (p.last[1] if p.last else frozenset()) or not any(axes)
                readings.append((p, axes, held))
            urgent = urgent or any(p.pressed for p in pads.values())
            due = now - last_publish
            coalescing = changed and not urgent and due < self.min_interval
            if urgent or (changed and not coalescing) or (pads and due >= HEARTBEAT):
                frame = GamepadFrame(now, tuple(PadReading(p.pad, axes, held, tuple(p.pressed))
                                                for p, axes, held in readings), tuple(added), tuple(removed))
                for p, axes, held in readings:
                    p.last = (axes, held)
                    p.pressed = []
                added, removed, first = [], [], False
                last_publish = now
                self._publish(frame)

    def _wait(self, stop: threading.Event, ev, pads: dict[int, _Open], coalescing: bool,
              last_publish: float) -> bool:
        """Until an event (True: it is in ``ev``) or the next frame is due. With a pad open, SDL waits: it polls
        the devices every millisecond in C, without holding Python's lock; a moving stick's frames are spaced
        by ``min_interval`` (its events wait in SDL's queue meanwhile); with none, a slow poll for hot-plug."""
        if not pads:
            stop.wait(IDLE_PERIOD)
            return bool(sdl2.SDL_PollEvent(ctypes.byref(ev)))
        if coalescing:
            stop.wait(max(0.0, last_publish + self.min_interval - time.monotonic()))
            return bool(sdl2.SDL_PollEvent(ctypes.byref(ev)))
        wait_ms = int(1000 * (last_publish + HEARTBEAT - time.monotonic()))
        return bool(sdl2.SDL_WaitEventTimeout(ctypes.byref(ev), max(1, min(wait_ms, 50))))

    @staticmethod
    def _event(ev, pads: dict[int, _Open], added: list[Pad], removed: list[Pad]) -> None:
        kind = ev.type
        if kind == sdl2.SDL_JOYDEVICEADDED:
            GamepadReader._open(pads, ev.jdevice.which, added)
        elif kind == sdl2.SDL_JOYDEVICEREMOVED:
            gone = pads.pop(ev.jdevice.which, None)
            if gone is not None:
                gone.close()
                removed.append(gone.pad)
                log.info("gamepad disconnected: %s", gone.pad.name)
        elif kind == sdl2.SDL_CONTROLLERBUTTONDOWN:
            p = pads.get(ev.cbutton.which)
            if p is not None and p.controller:
                p.pressed.append(p.button_name(ev.cbutton.button))
        elif kind == sdl2.SDL_JOYBUTTONDOWN:
            p = pads.get(ev.jbutton.which)
            if p is not None and not p.controller:
                p.pressed.append(p.button_name(ev.jbutton.button))
        elif kind == sdl2.SDL_JOYHATMOTION:
            p = pads.get(ev.jhat.which)
            if p is not None and not p.controller:
                p.pressed += [f"hat{ev.jhat.hat}{d}" for d in _hat_directions(ev.jhat.value)]


_shared: GamepadReader | None = None
_shared_lock = threading.Lock()


def shared_reader() -> GamepadReader:
    """The process's reader (SDL's joysticks are process-wide)."""
    global _shared
    with _shared_lock:
        if _shared is None:
            _shared = GamepadReader()
        return _shared


class VirtualPad:
    """SDL's virtual joystick: a real SDL device with no hardware behind it (tests, benches, demos).

    ``controller=True`` attaches one SDL knows as a game controller (standard layout); otherwise a raw joystick
    with ``axes`` axes, ``buttons`` buttons and ``hats`` hats, as an RC transmitter in joystick mode appears.
    Values are set from the caller's thread; SDL locks its joysticks itself.
    """

    def __init__(self, name: str = "Virtual gamepad", controller: bool = True, axes: int = 6, buttons: int = 15,
                 hats: int = 0) -> None:
        if sdl2 is None:
            raise RuntimeError(_IMPORT_ERROR)
        _hints()
        if sdl2.SDL_InitSubSystem(_SUBSYSTEMS) != 0:
            raise RuntimeError(sdl2.SDL_GetError().decode(errors="replace"))
        desc = sdl2.SDL_VirtualJoystickDesc()
        desc.version = sdl2.SDL_VIRTUAL_JOYSTICK_DESC_VERSION
        desc.type = sdl2.SDL_JOYSTICK_TYPE_GAMECONTROLLER if controller else sdl2.SDL_JOYSTICK_TYPE_UNKNOWN
        desc.naxes = sdl2.SDL_CONTROLLER_AXIS_MAX if controller else axes
        desc.nbuttons = sdl2.SDL_CONTROLLER_BUTTON_MAX if controller else buttons
        desc.nhats = 0 if controller else hats
        self._name = name.encode()
        desc.name = self._name
        index = sdl2.SDL_JoystickAttachVirtualEx(ctypes.byref(desc))
        if index < 0:
            sdl2.SDL_QuitSubSystem(_SUBSYSTEMS)
            raise RuntimeError(sdl2.SDL_GetError().decode(errors="replace"))
        self.controller = controller
        self._joystick = sdl2.SDL_JoystickOpen(index)
        self.centre()
        self.instance = sdl2.SDL_JoystickInstanceID(self._joystick)
        self.guid = _guid_text(sdl2.SDL_JoystickGetGUID(self._joystick))
        self.name = name
        self.attached = True

    _AXES = {"leftx": 0, "lefty": 1, "rightx": 2, "righty": 3, "lefttrigger": 4, "righttrigger": 5}
    _BUTTONS = {"a": 0, "b": 1, "x": 2, "y": 3, "back": 4, "guide": 5, "start": 6, "leftstick": 7,
                "rightstick": 8, "leftshoulder": 9, "rightshoulder": 10, "dpup": 11, "dpdown": 12, "dpleft": 13,
                "dpright": 14}

    def set_axis(self, axis: str | int, value: float) -> None:
        """``value`` in [-1, 1] as the reader will report it (a controller's y axes: + is up)."""
        if isinstance(axis, str):
            flip = axis in ("lefty", "righty")
            axis = self._AXES[axis] if axis in self._AXES else int(axis.removeprefix("axis"))
            value = -value if flip else value
        if self.controller and axis in (self._AXES["lefttrigger"], self._AXES["righttrigger"]):
            value = 2.0 * value - 1.0          # a trigger's 0..1 is the device's whole range
        raw = int(round(max(-1.0, min(1.0, value)) * 32767))
        sdl2.SDL_JoystickSetVirtualAxis(self._joystick, axis, raw)

    def set_button(self, button: str | int, down: bool) -> None:
        if isinstance(button, str):
            button = self._BUTTONS[button] if button in self._BUTTONS else int(button.removeprefix("button"))
        sdl2.SDL_JoystickSetVirtualButton(self._joystick, button, 1 if down else 0)

    def centre(self) -> None:
        """Sticks to the centre, triggers released."""
        for axis in range(sdl2.SDL_JoystickNumAxes(self._joystick)):
            trigger = self.controller and axis in (self._AXES["lefttrigger"], self._AXES["righttrigger"])
            sdl2.SDL_JoystickSetVirtualAxis(self._joystick, axis, -32768 if trigger else 0)

    def detach(self) -> None:
        """Unplug it (the reader sees it removed)."""
        if not self.attached:
            return
        self.attached = False
        for index in range(sdl2.SDL_NumJoysticks()):
            if sdl2.SDL_JoystickGetDeviceInstanceID(index) == self.instance:
                sdl2.SDL_JoystickClose(self._joystick)
                sdl2.SDL_JoystickDetachVirtual(index)
                break
        sdl2.SDL_QuitSubSystem(_SUBSYSTEMS)


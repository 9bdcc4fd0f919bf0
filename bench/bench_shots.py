"""The smart shots measured: every shot flown through the driver and judged on what the vehicle really did.

    .venv/bin/python bench/bench_shots.py [--speedup 1] [--loss 0] [--markdown]        # the simulated vehicle
    .venv/bin/python bench/bench_shots.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter [--loss 0.3]

On the simulator the truth is ``SimVehicle.truth()`` and the driver runs on the simulator's clock (so a
``--speedup`` changes nothing the table measures). On real ArduCopter SITL the truth is SERIAL1, read with plain
pymavlink (bench/sitl_judge.py); the driver reaches SERIAL0 through bench/lossy_relay.py (``--loss`` each way),
and the SITL runs ArduPilot's copter.parm with copter-gimbal.parm (MNT1_TYPE 1: a servo gimbal on SERVO5-7,
RC6 its pitch), a servo camera (CAM1_TYPE 1: a picture is CAMERA_FEEDBACK) and FOLL_ENABLE 1.

Rows (the goals are the smart shots' own): the cable's path error (RMS, 4 keyframes at 5 m/s), the vehicle's
acceleration (averaged over 0.5 s) and the one the shot asks for, the camera's aim along the cable (RMS), the orbit's
radius error (RMS, 20 m at 3 m/s) and its camera on the centre, the follow distance kept to a target walking at
1.5 m/s (GUIDED and ArduCopter's FOLLOW), the selfie and the pano, Stop from the press to the vehicle braking,
and with ``--loss``: the driver's reports that were wrong (checked against the truth of the last 1.5 s, as
telemetry lags) and whether each shot completed or was honestly stopped.
"""
from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
from dataclasses import dataclass

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


from pymavlink.quaternion import Quaternion  # noqa: E402

import tables  # noqa: E402
from lossy_relay import LossyRelay, free_udp_port  # noqa: E402
from real_sitl import HOME, SHIM, Sitl  # noqa: E402
from sitl_judge import Judge  # noqa: E402

from driver import Vehicle, VehicleConfig  # noqa: E402
from driver.core.frames import offset_latlon, offset_ned  # noqa: E402
from driver.shots.model import Keyframe, ShotPhase  # noqa: E402
from driver.shots.spline import Looks, PathRun, SpeedProfile, Spline  # noqa: E402

CABLE = [(0.0, 0.0, 10.0), (30.0, 10.0, 15.0), (40.0, 50.0, 12.0), (10.0, 70.0, 20.0)]
LOOKS = [(-10.0, 0.0), (-30.0, 90.0), (-20.0, 180.0), (-45.0, 270.0)]
LAG = 1.5                    # s: a report is right if the truth of the last LAG seconds agrees with it


@dataclass
class Sample:
    time: float
    north: float
    east: float
    up: float
    vn: float
    ve: float
    vd: float
    heading: float           # degrees: where the camera faces (the nose, turned by the gimbal's yaw where it has one)
    pitch: float | None      # the gimbal's, degrees
    mode: str
    nose: float = 0.0        # degrees: the vehicle's own heading

    @property
    def where(self) -> tuple[float, float, float]:
        return self.north, self.east, self.up

    @property
    def speed(self) -> float:
        return math.hypot(self.vn, self.ve)


class SimRig:
    """driver.sim's vehicle; the driver on its clock."""
    name = "simulator"

    def __init__(self, speedup: float, loss: float, seed: int):
        from driver.sim import SimConfig, SimVehicle
        self.sim = SimVehicle(SimConfig(tcp_port=0, speedup=speedup, ready_after=1.0, seed=seed, camera=True,
                                        home=HOME)).start()
        self.sim.faults.uplink.loss = self.sim.faults.downlink.loss = loss
        self.vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{self.sim.tcp_port}", param_cache=None),
                               clock=self.now).start()

    def now(self) -> float:
        return self.sim.truth().time

    def sample(self) -> Sample:
        t = self.sim.truth()
        return Sample(t.time, t.north, t.east, t.altitude, t.vn, t.ve, t.vd, t.heading_deg, t.mount_pitch, t.mode,
                      t.heading_deg)

    def photos(self) -> int:
        return self.sim.autopilot.images

    def close(self) -> None:
        self.vehicle.close()
        self.sim.stop()


class SitlRig:
    """Real ArduCopter SITL: the driver through the lossy relay, the truth on SERIAL1."""
    name = "ArduCopter 4.6.3 SITL"

    def __init__(self, binary: str, shim: str, loss: float, seed: int, scratch: str, instance: int):
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(binary)))))
        params = os.path.join(root, "Tools", "autotest", "default_params")
        defaults = os.path.join(scratch, "shots.parm")
        with open(defaults, "w") as out:
            for name in ("copter.parm", "copter-gimbal.parm"):
                with open(os.path.join(params, name)) as f:
                    out.write(f.read() + "\n")
            out.write("CAM1_TYPE 1\nFOLL_ENABLE 1\n")
        self.sitl = Sitl(binary, instance, scratch, shim, defaults)
        self.sitl.start()
        self.relay = LossyRelay(5760 + 10 * instance, free_udp_port(), loss, seed, 30.0)
        with contextlib.redirect_stdout(sys.stderr):
            self.judge = Judge(5762 + 10 * instance, 30.0)
        self.judge.ask_streams({33: 50_000, 30: 50_000, 285: 100_000, 180: 1_000_000})   # position, attitude,
        port = free_udp_port()                                                            # gimbal, camera
        self.relay.retarget(port)
        self.vehicle = Vehicle(VehicleConfig(connection=f"udpin:127.0.0.1:{port}", param_cache=None)).start()
        self._photos = 0
        self._seen_feedback = None
        self._last_pos = self._last = None

    def now(self) -> float:
        return time.monotonic()

    def sample(self) -> Sample | None:
        j = self.judge
        pos, att, gim, hb, home = (j.latest(n, 2.0) for n in ("GLOBAL_POSITION_INT", "ATTITUDE",
                                                                   "GIMBAL_DEVICE_ATTITUDE_STATUS", "HEARTBEAT",
                                                                   "HOME_POSITION"))
        if pos is None or att is None or home is None:
            return None
        if pos is self._last_pos:                  # a sample a GLOBAL_POSITION_INT, timed as it came
            return self._last
        self._last_pos = pos
        n, e = offset_ned(home.latitude / 1e7, home.longitude / 1e7, pos.lat / 1e7, pos.lon / 1e7)
        heading, pitch = math.degrees(att.yaw) % 360.0, None
        if gim is not None:
            # where the mount aims the camera: AP_Mount_Servo (MNT1_TYPE 1) reports its servos' body-frame angles
            # ("demanded servo angles", AP_Mount_Servo::get_attitude_quaternion), whatever the flags say: the
            # earth-frame target less the vehicle's lean turned to the mount's yaw (update_angle_outputs). The
            # lean added back, as that function took it away, gives the look the mount flies the camera to.
            _, pitch_bf, yaw_bf = Quaternion(list(gim.q)).euler
            lean_pitch = math.sin(-yaw_bf) * att.roll + math.cos(-yaw_bf) * att.pitch     # Vector2f::rotate
            pitch = math.degrees(pitch_bf + lean_pitch)
            heading = (heading + math.degrees(yaw_bf)) % 360.0
        self._last = Sample(time.monotonic(), n, e, pos.relative_alt / 1000.0, pos.vx / 100.0, pos.vy / 100.0,
                            pos.vz / 100.0, heading, pitch, j.mode, math.degrees(att.yaw) % 360.0)
        return self._last

    def photos(self) -> int:
        fb = self.judge.latest("CAMERA_FEEDBACK", 1e9)
        if fb is not None and fb is not self._seen_feedback:
            self._seen_feedback = fb
            self._photos = fb.img_idx
        return self._photos

    def close(self) -> None:
        self.vehicle.close()
        self.judge.close()
        self.relay.close()
        self.sitl.stop()


# -- flying and judging ----------------------------------------------------------------------------------------
class Flight:
    def __init__(self, rig):
        self.rig, self.v = rig, rig.vehicle
        self.rows: list[tuple[str, str, str, str]] = []
        self.wrong: list[str] = []
        self.outcomes: list[str] = []

    def latlon(self, north: float, east: float) -> tuple[float, float]:
        home = self.v.state().home
        return offset_latlon(home.lat, home.lon, north, east)

    def fly(self, seconds: float, until=None, each=None) -> list[tuple[Sample, object]]:
        """(truth, driver state) pairs at the truth's own rate for ``seconds`` of the vehicle's time."""
        out, start, last = [], self.rig.now(), None
        while self.rig.now() - start < seconds:
            s = self.rig.sample()
            if s is None or (last is not None and s.time == last.time):
                time.sleep(0.005)
                continue
            last = s
            state = self.v.state()
            out.append((s, state))
            if each is not None:
                each(s, state)
            if until is not None and until(s, state):
                break
        return out

    def row(self, figure: str, value: str, goal: str, ok: bool | None) -> None:
        verdict = "-" if ok is None else "within" if ok else "OVER"
        self.rows.append((figure, value, goal, verdict))
        print(f"  {figure}: {value} ({goal}) {verdict}", file=sys.stderr, flush=True)

    def reports(self, shot: str, samples, check) -> None:
        """Count the reports ``check(state, recent truth)`` calls wrong: only fresh ones (a changed report)."""
        last = None
        for i, (s, state) in enumerate(samples):
            shot_state = state.shot
            if shot_state is last:
                continue
            last = shot_state
            recent = [t for t, _ in samples[max(0, i - 400):i + 1] if s.time - t.time <= LAG]
            why = check(shot_state, recent)
            if why:
                self.wrong.append(f"{shot}: {why}")

    def ended(self, shot: str, samples, completed) -> None:
        s, state = samples[-1]
        phase = state.shot.phase
        if phase is ShotPhase.ENDED:
            self.outcomes.append(f"{shot}: stopped ({state.shot.detail})")
        elif completed(s, state):
            self.outcomes.append(f"{shot}: completed")
        else:
            self.outcomes.append(f"{shot}: NOT completed ({state.shot.describe()})")
            self.wrong.append(f"{shot}: neither completed nor stopped: {state.shot.describe()}")

    def hover_at(self, north: float, east: float, up: float) -> None:
        """A go-to (a single message: sent again until the vehicle is on its way, as a lossy link drops it)."""
        there = lambda s: (s.local is not None and math.hypot(s.local.north - north, s.local.east - east) < 0.5   # noqa: E731
                           and abs(s.altitude - up) < 0.5 and s.velocity.ground_speed < 0.2)
        for _ in range(10):
            if self.v.state().mode != "GUIDED":
                self.v.set_mode("GUIDED").result(30)
            self.v.go_to(north, east, up).result(30)
            if self.v.wait_for(lambda s: there(s) or s.velocity.ground_speed > 0.5, 5) and \
                    self.v.wait_for(there, 90):
                return


def aim(s: Sample, pitch: float, yaw: float) -> float | None:
    if s.pitch is None:
        return None
    p1, y1, p2, y2 = (math.radians(v) for v in (s.pitch, s.heading, pitch, yaw))
    c = math.sin(p1) * math.sin(p2) + math.cos(p1) * math.cos(p2) * math.cos(y1 - y2)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def split(samples, want) -> str:
    """The aim's error as pitch and heading RMS: where a camera that is off looks off."""
    p = [s.pitch - want(s)[0] for s in samples if s.pitch is not None]
    y = [(s.heading - want(s)[1] + 180.0) % 360.0 - 180.0 for s in samples]
    n = [(s.nose - want(s)[1] + 180.0) % 360.0 - 180.0 for s in samples]
    return (f"pitch {rms(p):.1f}° (mean {sum(p) / max(len(p), 1):+.1f}), heading {rms(y):.1f}° "
            f"(mean {sum(y) / max(len(y), 1):+.1f}); the nose alone {rms(n):.1f}° (mean {sum(n) / max(len(n), 1):+.1f})")


def look(s: Sample, point) -> tuple[float, float]:
    dn, de, du = point[0] - s.north, point[1] - s.east, point[2] - s.up
    return math.degrees(math.atan2(du, math.hypot(dn, de))), math.degrees(math.atan2(de, dn)) % 360.0


def rms(values) -> float:
    values = [v for v in values if v is not None]
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else float("nan")


def accelerations(samples, window: float = 0.5) -> list[float]:
    """The vehicle's acceleration, each averaged over ``window`` s."""
    out, j = [], 0
    for i, (s, _) in enumerate(samples):
        while samples[j][0].time < s.time - window:
            j += 1
        a = samples[j][0]
        if s.time - a.time >= 0.8 * window:
            dt = s.time - a.time
            out.append(math.sqrt((s.vn - a.vn) ** 2 + (s.ve - a.ve) ** 2 + (s.vd - a.vd) ** 2) / dt)
    return out


def cable(f: Flight) -> None:
    f.hover_at(*CABLE[0])
    keys = [Keyframe(*f.latlon(n, e), u, p, y) for (n, e, u), (p, y) in zip(CABLE, LOOKS)]
    assert f.v.shots.set_keyframes(keys).result(30).ok
    started = f.v.shots.cable(speed=5.0).result(60)
    if not started.ok:
        f.row("cable cam", str(started), "starts", False)
        return
    samples = f.fly(150.0, until=lambda s, st: not st.shot.active or st.shot.phase is ShotPhase.PAUSED)
    sp, lk = Spline(CABLE), Looks(LOOKS)
    riding = [(s, st) for s, st in samples if st.shot.phase is ShotPhase.FLYING]
    errors = [math.dist(s.where, sp.point(sp.nearest(s.where))) for s, _ in riding]
    f.row("cable cam path error (RMS), 4 keyframes, 5 m/s", f"{rms(errors):.2f} m (max {max(errors):.2f})",
          "≤ 0.5 m", rms(errors) <= 0.5)
    off = [(s.where, sp.point(sp.nearest(s.where))) for s, _ in riding]
    late = [e for (s, _), e in zip(riding, errors) if s.time >= riding[0][0].time + 3.0]
    print(f"    after the first 3 s on the cable {rms(late):.2f} m; by quarter of the samples: " + ", ".join(
        f"{rms(errors[i * len(errors) // 4:(i + 1) * len(errors) // 4]):.2f}" for i in range(4)), file=sys.stderr)
    print(f"    horizontal {rms(math.hypot(a[0] - b[0], a[1] - b[1]) for a, b in off):.2f} m, vertical "
          f"{rms(a[2] - b[2] for a, b in off):.2f} m (mean {sum(a[2] - b[2] for a, b in off) / len(off):+.2f})",
          file=sys.stderr)
    acc = accelerations(riding)
    run = PathRun(SpeedProfile(sp, 8.0))
    asked, prev = [], None
    while not (run.at_end and run.speed == 0.0):
        run.step(0.1, 5.0)
        v = run.velocity()
        if prev is not None:
            asked.append(math.dist(v, prev) / 0.1)
        prev = v
    f.row("acceleration the cable asks for (max)", f"{max(asked):.2f} m/s²", "≤ 2.0 m/s²", max(asked) <= 2.0 + 1e-6)
    f.row("acceleration the vehicle flew (max, 0.5 s average)", f"{max(acc):.2f} m/s²", "≤ 2.0 m/s²",
          max(acc) <= 2.0)
    aims = [aim(s, *lk.at(float(sp.param(sp.nearest(s.where))))) for s, _ in riding[20:]]
    f.row("camera aim error at the keyframes' looks, interpolated (RMS)", f"{rms(aims):.2f}°", "≤ 2° RMS",
          rms(aims) <= 2.0)
    print("    " + split([s for s, _ in riding[20:]], lambda s: lk.at(float(sp.param(sp.nearest(s.where))))),
          file=sys.stderr)
    f.reports("cable", samples, lambda st, recent: (
        None if st.progress is None or any(abs(st.progress * sp.length - sp.nearest(t.where)) < 1.5 for t in recent)
        else f"progress {st.progress:.3f} reported, the vehicle at "
             f"{sp.nearest(recent[-1].where) / sp.length:.3f}"))
    f.ended("cable", samples, lambda s, st: math.dist(s.where, CABLE[-1]) < 2.0)
    f.v.shots.stop().result(30)
    f.fly(3.0)


def orbit_and_stop(f: Flight) -> None:
    f.hover_at(0.0, 0.0, 10.0)
    lat, lon = f.latlon(20.0, 0.0)
    started = f.v.shots.orbit(lat, lon, 0.0, radius=20.0, speed=3.0).result(60)
    if not started.ok:
        f.row("orbit", str(started), "starts", False)
        return
    samples = f.fly(60.0)
    centre = (20.0, 0.0, 0.0)
    flying = [(s, st) for s, st in samples if st.shot.phase is ShotPhase.FLYING]
    flying = [(s, st) for s, st in flying if s.time >= flying[0][0].time + 1.0]      # on the circle, settled
    radius = [math.hypot(s.north - 20.0, s.east) - 20.0 for s, _ in flying]
    f.row("orbit radius error (RMS) at 20 m, 3 m/s", f"{rms(radius):.2f} m", "≤ 0.5 m", rms(radius) <= 0.5)
    aims = [aim(s, *look(s, centre)) for s, _ in flying]
    worst = max(a for a in aims if a is not None)
    f.row("orbit: camera on the centre", f"{rms(aims):.2f}° RMS, max {worst:.2f}°", "≤ 2°", rms(aims) <= 2.0)
    print("    " + split([s for s, _ in flying], lambda s: look(s, centre)), file=sys.stderr)
    f.reports("orbit", samples, lambda st, recent: (
        None if st.radius is None or any(abs(st.radius - math.hypot(t.north - 20.0, t.east)) < 1.0 for t in recent)
        else f"radius {st.radius:.1f} m reported, the vehicle at {math.hypot(recent[-1].north - 20, recent[-1].east):.1f} m"))
    f.ended("orbit", samples, lambda s, st: st.shot.phase is ShotPhase.FLYING)
    # Stop: from the press to the vehicle braking
    cruising = f.rig.sample().speed
    pressed = f.rig.now()
    f.v.stop()
    braking = f.fly(5.0, until=lambda s, st: s.speed < cruising - 0.1)        # 0.1 m/s slower than at the press
    took = braking[-1][0].time - pressed
    f.row("Stop, from the press to the vehicle braking", f"{took:.2f} s (from {cruising:.1f} m/s)", "≤ 0.5 s",
          took <= 0.5)
    f.fly(5.0)


def follow(f: Flight, engine: str) -> None:
    f.hover_at(0.0, 0.0, 10.0)
    start = (-15.0, 0.0)
    t0 = f.rig.now()
    on = threading.Event()
    on.set()
    gone = threading.Event()

    def where(t: float) -> tuple[float, float, float]:
        return start[0], start[1] + 1.5 * (t - t0), 0.0

    def walk() -> None:
        last = -1.0
        home = f.v.state().home
        while not gone.is_set():
            now = f.rig.now()
            if on.is_set() and now - last >= 0.5:
                last = now
                n, e, _ = where(now)
                f.v.shots.follow_position(*f.latlon(n, e), home.alt, 0.0, 1.5)
            time.sleep(0.01)
    threading.Thread(target=walk, daemon=True).start()
    f.fly(1.5)
    started = f.v.shots.follow("given", engine).result(60)
    if not started.ok:
        f.row(f"follow ({engine})", str(started), "starts", False)
        gone.set()
        return
    samples = f.fly(45.0)
    kept = [math.dist(s.where, where(s.time)) for s, _ in samples[20:]]
    wanted = kept[0]
    f.row(f"follow ({engine.upper()}): distance kept (RMS) to a target walking at 1.5 m/s",
          f"{rms(d - wanted for d in kept):.2f} m at {wanted:.1f} m", "≤ 1 m", rms(d - wanted for d in kept) <= 1.0)
    f.reports(f"follow {engine}", samples, lambda st, recent: (
        None if st.target_distance is None or any(abs(st.target_distance - math.dist(t.where, where(t.time))) < 1.5
                                                  for t in recent)
        else f"target {st.target_distance:.1f} m reported"))
    on.clear()
    held = f.fly(20.0, until=lambda s, st: st.shot.phase is ShotPhase.HOLDING and s.speed < 0.3)
    s, st = held[-1]
    f.row(f"follow ({engine.upper()}): the target's fixes stop", f"{st.shot.phase.value} at {s.speed:.2f} m/s: "
          f"{st.shot.detail}", "holds and says so", st.shot.phase is ShotPhase.HOLDING and s.speed < 0.3)
    gone.set()
    f.ended(f"follow {engine}", held, lambda s, st: st.shot.phase is ShotPhase.HOLDING)
    f.v.stop().result(30)
    f.fly(3.0)


def selfie(f: Flight) -> None:
    f.hover_at(8.0, 0.0, 10.0)
    begin = f.rig.sample()
    started = f.v.shots.selfie(distance=20.0, rise=10.0, speed=3.0).result(60)
    if not started.ok:
        f.row("selfie", str(started), "starts", False)
        return
    samples = f.fly(90.0, until=lambda s, st: not st.shot.active)
    end = samples[-1][0]
    far = max((s for s, _ in samples), key=lambda s: s.north)
    out = math.dist(far.where, (begin.north + 20.0, begin.east, begin.up + 10.0))
    back = math.dist(end.where, begin.where)
    moving = [s for s, st in samples if st.shot.phase is ShotPhase.FLYING and math.dist(s.where, begin.where) > 0.5]
    aims = [aim(s, *look(s, (0.0, 0.0, 0.0))) for s in moving]
    print("    " + split(moving, lambda s: look(s, (0.0, 0.0, 0.0))), file=sys.stderr)
    f.row("selfie: out 20 m and up 10 m and back, the camera on the pilot",
          f"far end {out:.2f} m off, back {back:.2f} m off, camera {rms(aims):.2f}° RMS", "≤ 1 m, ≤ 2°",
          out <= 1.0 and back <= 1.0 and rms(aims) <= 2.0)
    f.ended("selfie", samples, lambda s, st: st.shot.phase is ShotPhase.DONE and back <= 1.0)


def pano(f: Flight) -> None:
    before = f.rig.photos()
    started = f.v.shots.pano("cylinder", 360.0, 74.0, -10.0).result(60)
    if not started.ok:
        f.row("pano", str(started), "starts", False)
        return
    samples = f.fly(180.0, until=lambda s, st: not st.shot.active)
    st = samples[-1][1].shot
    taken = f.rig.photos() - before
    f.row("pano: a confirmed picture at each step (cylinder, 8 steps)",
          f"{st.photos} reported of {st.photos_total}, the camera took {taken}", "8 = 8",
          st.photos == st.photos_total == taken)
    f.reports("pano", samples, lambda st, recent: None if st.photos <= f.rig.photos() - before
              else f"{st.photos} pictures reported, {f.rig.photos() - before} taken")
    f.ended("pano", samples, lambda s, st: st.shot.phase is ShotPhase.DONE and st.shot.photos == st.shot.photos_total)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sitl", metavar="PATH", help="real ArduCopter SITL binary (else the simulated vehicle)")
    ap.add_argument("--shim", default=SHIM, help="LD_PRELOAD library keeping the SITL on 127.0.0.1")
    ap.add_argument("--instance", type=int, default=6, help="SITL instance: ports 5760/5762 + 10*N")
    ap.add_argument("--speedup", type=float, default=1.0, help="the simulator's pace (the figures do not change)")
    ap.add_argument("--loss", type=float, default=0.0, help="share of frames lost each way")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--only", help="comma-separated: cable,orbit,follow,selfie,pano")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    scratch = tempfile.mkdtemp(prefix="bench-shots-")
    for var in ("XDG_STATE_HOME", "XDG_CACHE_HOME"):
        os.environ[var] = scratch
    started = time.monotonic()
    rig = None

    def on_signal(number, _frame):
        raise SystemExit(128 + number)                 # runs the finally below: the SITL is stopped
    for number in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(number, on_signal)
    try:
        rig = (SitlRig(args.sitl, args.shim, args.loss, args.seed, scratch, args.instance) if args.sitl
               else SimRig(args.speedup, args.loss, args.seed))
        v = rig.vehicle
        assert v.wait_for(lambda s: s.connected and s.readiness.ready_to_arm, 180), "not ready to arm"
        print(f"ready to arm at {time.monotonic() - started:.0f} s", file=sys.stderr, flush=True)
        assert v.fetch_parameters().result(180).ok
        took = v.takeoff(10.0).result(120)
        assert took.ok, str(took)
        print(f"flying at {time.monotonic() - started:.0f} s", file=sys.stderr, flush=True)
        f = Flight(rig)
        wanted = set((args.only or "cable,orbit,follow,selfie,pano").split(","))
        if args.sitl is None and "follow" in wanted:
            assert v.set_parameter("FOLL_ENABLE", 1).result(30).ok and v.fetch_parameters().result(180).ok
        for name, run in (("cable", cable), ("orbit", orbit_and_stop), ("follow", lambda f: follow(f, "guided")),
                          ("follow", lambda f: follow(f, "follow")), ("selfie", selfie), ("pano", pano)):
            if name in wanted:
                print(f"{name} at {time.monotonic() - started:.0f} s", file=sys.stderr, flush=True)
                try:
                    run(f)
                except Exception as exc:  # noqa: BLE001 - the rows so far are printed, and the failure with them
                    f.row(name, f"bench stopped: {type(exc).__name__}: {exc}", "-", False)
                    f.v.stop()
        title = f"{rig.name}, {args.loss:.0%} loss each way"
        f.row(f"reports checked against the truth ({title})", f"{len(f.wrong)} wrong", "0 wrong", not f.wrong)
        f.row("every shot completes or is honestly stopped", "; ".join(f.outcomes), "all", not any(
            "NOT" in o for o in f.outcomes))
        print(f"\n{title}\n")
        print("\n".join(tables.render(("figure", "measured", "goal", "verdict"), f.rows, args.markdown)))
        for why in f.wrong[:20]:
            print(f"  wrong: {why}")
        print(f"(whole run {time.monotonic() - started:.0f} s)")
        return 1 if any(r[3] == "OVER" for r in f.rows) else 0
    finally:
        if rig is not None:
            rig.close()
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())

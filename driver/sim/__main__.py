"""python -m driver.sim: a simulated ArduCopter any MAVLink ground station can fly.

    python -m driver.sim                          # tcp:127.0.0.1:5760 like SITL
    python -m driver.sim --udp-out 127.0.0.1:14550 --profile solo --gimbal   # like a stock 3DR Solo
    python -m driver.sim --uplink-loss 0.1 --downlink-loss 0.1 --latency 0.2 --jitter 0.05 --lose-replies
    python -m driver.sim --usb-port 5761 --signing-passphrase secret   # signing on; unsigned only on 5761
    python -m driver.sim --count 3                # three vehicles on tcp 5760, 5761, 5762: system ids 1-3, homes 10 m apart
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..options import accepted_by, not_negative, number, positive, whole
from .faults import LinkFaults
from .profiles import PROFILES, speaks_mavlink2
from .server import parse_address
from .signing import passphrase_key
from .vehicle import SimConfig, SimVehicle

share = number(0.0, 1.0, "a share from 0 to 1 is needed")

log = logging.getLogger("driver.sim")


def _home(text: str) -> tuple[float, float, float, float]:
    parts = [float(v) for v in text.split(",")]
    if len(parts) != 4:
        raise argparse.ArgumentTypeError("expected LAT,LON,ALT,HEADING")
    return parts[0], parts[1], parts[2], parts[3]


def _ned(text: str) -> tuple[float, float, float]:
    try:
        parts = tuple(float(v) for v in text.split(","))
    except ValueError:
        parts = ()
    if len(parts) != 3 or not all(abs(v) < 1e4 for v in parts):
        raise argparse.ArgumentTypeError(f"{text!r}: expected NORTH,EAST,DOWN in metres")
    return parts


def _replies(text: str):
    """"all", a share from 0 to 1 (with a point: 0.5), or MAV_CMD ids/names separated by commas."""
    if text == "all":
        return True
    if "." in text:
        return share(text)
    ids = set()
    by_name = {entry.name.removeprefix("MAV_CMD_"): number for number, entry in mavlink.enums["MAV_CMD"].items()}
    for part in text.split(","):
        part = part.strip().upper().removeprefix("MAV_CMD_")
        if part.isdigit():
            ids.add(int(part))
        elif part in by_name:
            ids.add(by_name[part])
        else:
            raise argparse.ArgumentTypeError(f"{text!r}: expected all, a share like 0.5, or MAV_CMD ids or names")
    return ids


_address = accepted_by(parse_address)       # HOST:PORT, with the port's range checked


def parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m driver.sim", description=__doc__.splitlines()[0])
    parser.add_argument("--tcp", type=_address, default="127.0.0.1:5760", metavar="HOST:PORT",
                        help="TCP server address (default 127.0.0.1:5760, port 0 = any)")
    parser.add_argument("--udp-out", type=_address, metavar="HOST:PORT",
                        help="push telemetry there, like the Solo's controller to 14550")
    parser.add_argument("--udp-in", type=_address, metavar="HOST:PORT",
                        help="serve UDP on this address, answering whoever sent last")
    parser.add_argument("--speedup", type=positive, default=1.0, help="sim seconds per real second")
    parser.add_argument("--ready-after", type=not_negative, default=SimConfig.ready_after, metavar="SECONDS",
                        help=f"sim seconds until ready to arm (GPS fix, EKF; default {SimConfig.ready_after:g})")
    parser.add_argument("--home", type=_home, default=SimConfig.home, metavar="LAT,LON,ALT,HEADING")
    parser.add_argument("--profile", choices=sorted(PROFILES), default=SimConfig.profile,
                        help="firmware: copter-4 (ArduCopter 4.x as recorded) or solo (stock 3DR Solo, 3.3 era)")
    parser.add_argument("--mav1", action="store_true", help="MAVLink 1 only (the solo profile implies it)")
    parser.add_argument("--origin-offset", type=_ned, default=SimConfig.origin_offset, metavar="N,E,D",
                        help="where the EKF origin is from home, metres (default %(default)s)")
    parser.add_argument("--gimbal", action="store_true", help="a gimbal (component 154) on the link, MAVLink 2")
    parser.add_argument("--companion", action="store_true", help="a companion computer (component 191)")
    parser.add_argument("--camera", action="store_true",
                        help="a camera on the vehicle: pictures are confirmed with CAMERA_FEEDBACK (copter-4)")
    parser.add_argument("--adsb", type=whole(0, 100), default=0, metavar="N",
                        help="N aircraft of ADS-B traffic around home (SITL's SIM_ADSB_COUNT, copter-4)")
    parser.add_argument("--calibration-model", action="store_true",
                        help="the airframe turns as the accel calibration asks and tumbles for the compass one")
    parser.add_argument("--log-dir", metavar="DIR",
                        help="keep the DataFlash logs (written while armed, 0000000N.BIN) here (default: a temp folder)")
    parser.add_argument("--radio-baud", type=whole(1200, 10_000_000), metavar="BAUD",
                        help="a telemetry radio of this baud (no flow control): parameters, logs and FTP keep to "
                             "its bandwidth, log download sends one LOG_DATA a call (the Solo: its 921,600-baud "
                             "flow-controlled link to the companion computer)")
    parser.add_argument("--usb-port", type=whole(0, 65535), metavar="PORT",
                        help="also serve TCP on this port (on --tcp's host, 0 = any) as the USB port, SERIAL0: "
                             "unsigned frames are accepted there even with signing on (--tcp is a telemetry port)")
    parser.add_argument("--signing-passphrase", metavar="TEXT",
                        help="start with MAVLink 2 signing on, key = SHA-256 of TEXT as MAVProxy's "
                             "'signing setup' makes it (needs MAVLink 2: not with --profile solo or --mav1)")
    faults = parser.add_argument_group("link faults (real seconds; shares from 0 to 1)")
    faults.add_argument("--uplink-loss", type=share, default=0.0, metavar="SHARE",
                        help="share of frames from the ground station lost")
    faults.add_argument("--downlink-loss", type=share, default=0.0, metavar="SHARE",
                        help="share of frames from the vehicle lost")
    faults.add_argument("--burst-rate", type=share, default=0.0, metavar="SHARE",
                        help="chance per frame, each way, that a burst of loss starts")
    faults.add_argument("--burst-seconds", type=not_negative, default=0.0, metavar="SECONDS",
                        help="how long a burst lasts")
    faults.add_argument("--duplicate", type=share, default=0.0, metavar="SHARE", help="frames delivered twice")
    faults.add_argument("--latency", type=not_negative, default=0.0, metavar="SECONDS", help="delay, each way")
    faults.add_argument("--jitter", type=not_negative, default=0.0, metavar="SECONDS",
                        help="the delay varies by up to this much")
    faults.add_argument("--reorder", type=share, default=0.0, metavar="SHARE",
                        help="frames held back behind the next one")
    faults.add_argument("--corrupt", type=share, default=0.0, metavar="SHARE",
                        help="frames from the vehicle with a flipped bit")
    faults.add_argument("--lose-replies", type=_replies, nargs="?", const=True, default=set(), metavar="WHICH",
                        help="the vehicle acts but its COMMAND_ACK is lost: all (default), a share like 0.3, "
                             "or MAV_CMD ids/names (NAV_TAKEOFF,400)")
    parser.add_argument("--count", type=whole(1, 250), default=1, metavar="N",
                        help="N vehicles on consecutive TCP ports from --tcp's, system ids 1 to N, homes 10 m apart "
                             "eastwards (a fleet: docs/fleet.md)")
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("-v", "--verbose", action="store_true")
    return parser


def configure(args: argparse.Namespace) -> SimVehicle:
    """The vehicle and its faults as the options say, not started yet."""
    host, port = parse_address(args.tcp)
    key = passphrase_key(args.signing_passphrase) if args.signing_passphrase is not None else None
    config = SimConfig(tcp_host=host, tcp_port=port, udp_out=args.udp_out, udp_listen=args.udp_in,
                       speedup=args.speedup, ready_after=args.ready_after, home=args.home,
                       mavlink2=not args.mav1, seed=args.seed, profile=args.profile,
                       origin_offset=args.origin_offset, gimbal=args.gimbal, companion=args.companion,
                       usb_port=args.usb_port, signing_key=key, camera=args.camera,
                       adsb=args.adsb, calibration_model=args.calibration_model,
                       log_dir=args.log_dir, radio_baud=args.radio_baud)
    return _with_faults(SimVehicle(config), args)


def configure_fleet(args: argparse.Namespace) -> list[SimVehicle]:
    """``--count`` vehicles as the options say (distinct system ids, homes and ports), not started yet."""
    from .fleet import fleet_configs
    first = configure(args)
    if args.count == 1:
        return [first]
    return [_with_faults(SimVehicle(c), args) for c in fleet_configs(args.count, first.config)]


def _with_faults(sim: SimVehicle, args: argparse.Namespace) -> SimVehicle:
    both = dict(burst_rate=args.burst_rate, burst_seconds=args.burst_seconds, duplicate=args.duplicate,
                latency=args.latency, jitter=args.jitter, reorder=args.reorder)
    sim.faults.uplink = LinkFaults(loss=args.uplink_loss, **both)
    sim.faults.downlink = LinkFaults(loss=args.downlink_loss, **both)
    sim.faults.corrupt_fraction = args.corrupt
    sim.faults.lose_replies = args.lose_replies
    return sim


def main(argv: list[str] | None = None) -> int:
    p = parser()
    args = p.parse_args(argv)
    if args.signing_passphrase is not None and (args.mav1 or not PROFILES[args.profile].mavlink2):
        p.error("--signing-passphrase needs MAVLink 2: not with --profile solo or --mav1")
    if args.count > 1 and (args.udp_out or args.udp_in or args.usb_port is not None):
        p.error("--count serves each vehicle on its own TCP port only: not with --udp-out, --udp-in or --usb-port")
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO,
                        format="%(asctime)s %(name)s: %(message)s")
    sims = configure_fleet(args)
    started = []
    for sim in sims:
        config = sim.config
        try:
            sim.start()
        except OSError as exc:
            for other in started:
                other.stop()
            return _cannot_serve(args, sim, exc)
        started.append(sim)
        log.info("simulated ArduCopter (%s), system id %d, at %.6f, %.6f (%s) on tcp:%s:%s", config.profile,
                 config.system_id, config.home[0], config.home[1],
                 "MAVLink 2" if speaks_mavlink2(config) else "MAVLink 1 only", config.tcp_host, sim.tcp_port)
    sim = sims[0]
    log.info("Ctrl-C to stop")
    if sim.signing.enabled:
        log.info("MAVLink 2 signing on: unsigned frames are dropped except on the USB port%s",
                 f" (tcp:{config.tcp_host}:{sim.usb_port})" if sim.usb_port is not None else " (none: --usb-port)")
    if sim.faults.uplink.active or sim.faults.downlink.active or args.corrupt or args.lose_replies:
        log.info("link faults: uplink %s, downlink %s, corrupt %g, lose replies %s", sim.faults.uplink,
                 sim.faults.downlink, args.corrupt, args.lose_replies or "none")
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    try:
        while not done.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        for sim in sims:
            sim.stop()
    return 0


def _cannot_serve(args: argparse.Namespace, sim: SimVehicle, exc: OSError) -> int:
    config = sim.config
    tcp_failed = config.tcp_port is not None and not sim.tcp_port
    usb_failed = config.usb_port is not None and sim.usb_port is None     # else the UDP socket failed
    where = (f"tcp:{config.tcp_host}:{config.tcp_port}" if tcp_failed
             else f"tcp:{config.tcp_host}:{config.usb_port}" if usb_failed else f"udp:{args.udp_in}")
    log.error("cannot serve MAVLink on %s: %s", where, (exc.strerror or str(exc)).lower())
    return 1


if __name__ == "__main__":
    sys.exit(main())

"""python -m driver.sim: a simulated ArduCopter any MAVLink ground station can fly.

    python -m driver.sim                          # tcp:127.0.0.1:5760 like SITL
    python -m driver.sim --udp-out 127.0.0.1:14550 --mav1   # like a stock 3DR Solo
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading

from ..options import not_negative, positive
from .server import parse_address
from .vehicle import SimConfig, SimVehicle

log = logging.getLogger("driver.sim")


def _home(text: str) -> tuple[float, float, float, float]:
    parts = [float(v) for v in text.split(",")]
    if len(parts) != 4:
        raise argparse.ArgumentTypeError("expected LAT,LON,ALT,HEADING")
    return parts[0], parts[1], parts[2], parts[3]


def _address(text: str) -> str:
    try:
        parse_address(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def main(argv: list[str] | None = None) -> int:
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
    parser.add_argument("--mav1", action="store_true", help="MAVLink 1 only, like a stock 3DR Solo")
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("-v", "--verbose", action="store_true")
    args = parser.parse_args(argv)

    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO,
                        format="%(asctime)s %(name)s: %(message)s")
    host, port = parse_address(args.tcp)
    config = SimConfig(tcp_host=host, tcp_port=port, udp_out=args.udp_out, udp_listen=args.udp_in,
                       speedup=args.speedup, ready_after=args.ready_after, home=args.home,
                       mavlink2=not args.mav1, seed=args.seed)
    sim = SimVehicle(config)
    try:
        sim.start()
    except OSError as exc:
        tcp_failed = config.tcp_port is not None and not sim.tcp_port      # else the UDP socket failed
        where = f"tcp:{args.tcp}" if tcp_failed else f"udp:{args.udp_in}"
        log.error("cannot serve MAVLink on %s: %s", where, (exc.strerror or str(exc)).lower())
        return 1
    log.info("simulated ArduCopter at %.6f, %.6f (%s); Ctrl-C to stop", config.home[0], config.home[1],
             "MAVLink 2" if config.mavlink2 else "MAVLink 1 only")
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    try:
        while not done.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        sim.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())

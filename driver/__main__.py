"""``python -m driver`` (installed: ``mavlinkserver``): the MAVLinkServer on the companion computer.

Connects to the autopilot (MAVProxy's options), serves JdeRobot's interfaces
and our extension over ZeroC Ice, and offers a console unless ``--daemon``::

    python -m driver --master udpin:0.0.0.0:14550 --Ice.Config=config/server.cfg
    python -m driver --sim --cmd "takeoff 3" --daemon
    python -m driver certs DIR --host 10.1.1.10          # then: --host 10.1.1.10 --certs DIR
    python -m driver registry                            # a lab's IceGrid registry and IceStorm (docs/fleet.md)
    python -m driver --sim --count 3 --registry 127.0.0.1:4061 --name sim --daemon   # sim-1, sim-2, sim-3
"""
from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
import time

from .options import (
    add_link_security, as_float, battery_threshold, battery_thresholds, connection, link_security, not_negative,
    port, positive, registry, takeoff_altitude,
    whole,
)
from .version import __version__

log = logging.getLogger("driver")

SOLO_MASTER = "udpin:0.0.0.0:14550"


def command_name() -> str:
    """What the pilot typed: ``mavlinkserver`` (the installed command) or ``python -m driver``."""
    return "mavlinkserver" if os.path.basename(sys.argv[0]) == "mavlinkserver" else "python -m driver"


def parser() -> argparse.ArgumentParser:
    from .sim import DEMO_READY_AFTER
    p = argparse.ArgumentParser(
        prog=command_name(),
        description="MAVLinkServer: MAVLink driver serving JdeRobot's interfaces over ZeroC Ice. "
                    "Ice options: --Ice.Config=FILE, --Ice.*=VALUE, --MAVLinkServer.*=VALUE (see config/server.cfg).")
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    p.add_argument("--master", type=connection,
                   help=f"MAVLink connection string (default {SOLO_MASTER}, the 3DR Solo; "
                        "tcp:HOST:PORT, udpin:, udpout:, a serial device, or a .tlog to replay)")
    p.add_argument("--baudrate", "--baud", type=whole(1, 10_000_000), default=57600,
                   help="serial baud rate (default 57600)")
    p.add_argument("--out", type=connection, action="append", default=[],
                   help="forward MAVLink to another ground station (repeatable), e.g. udp:127.0.0.1:14551")
    p.add_argument("--source-system", type=whole(1, 255), default=255, help="our MAVLink system id (default 255)")
    p.add_argument("--source-component", type=whole(0, 255), default=190,
                   help="our MAVLink component id (default 190)")
    p.add_argument("--target-system", type=whole(0, 255), default=0,
                   help="vehicle system id (default 0: the first heard)")
    p.add_argument("--target-component", type=whole(0, 255), default=1, help="vehicle component id (default 1)")
    p.add_argument("--streamrate", type=whole(1, 50), default=4, help="telemetry stream rate in Hz (default 4)")
    p.add_argument("--logfile", default="mav.tlog", help="telemetry log (default mav.tlog)")
    p.add_argument("--append-log", action="store_true", help="append to the log instead of replacing it")
    p.add_argument("--no-log", action="store_true", help="write no telemetry log")
    p.add_argument("--aircraft", help="aircraft name: logs go to NAME/logs/, shown in the prompt")
    p.add_argument("--cmd", action="append", default=[], help='console commands to run at start, ";"-separated')
    p.add_argument("--daemon", action="store_true", help="no interactive console; run until interrupted")
    p.add_argument("--param-metadata", metavar="FILE", help="ArduPilot's apm.pdef.xml for parameter bounds and "
                   "meanings (default: the per-user cache's, else the copy shipped for ArduCopter)")
    version = p.add_mutually_exclusive_group()
    version.add_argument("--mav10", action="store_true", help="speak MAVLink 1 only")
    version.add_argument("--mav20", action="store_true", help="speak MAVLink 2 from the start")
    add_link_security(p.add_argument_group("link security (docs/security.md)"))
    p.add_argument("--sim", action="store_true", help="fly the built-in simulated ArduCopter (in-process)")
    p.add_argument("--sim-speedup", type=positive, default=1.0, help="simulated time speed-up (default 1)")
    p.add_argument("--camera", action="append", default=[], metavar="URI",
                   help="video served as Camera, repeatable for Extra.toggleCam: 0, clip.mp4, rtsp://..., "
                        "udp://0.0.0.0:5600, solo, sim (default with --sim; see docs/camera.md)")
    p.add_argument("--sim-ready-after", type=not_negative, default=DEMO_READY_AFTER, metavar="SECONDS",
                   help=f"simulated seconds until the vehicle is ready to arm (default {DEMO_READY_AFTER:g})")
    p.add_argument("--takeoff-alt", type=takeoff_altitude,
                   help="default takeoff altitude in metres above home (default 3)")
    p.add_argument("--battery-warning", type=battery_threshold, metavar="VOLTS,PERCENT",
                   help="our own battery warning: volts a cell under load, percent remaining, whichever comes "
                        "first, whatever the vehicle's failsafe says (default 3.6,30)")
    p.add_argument("--battery-critical", type=battery_threshold, metavar="VOLTS,PERCENT",
                   help="our own battery critical alarm, as --battery-warning (default 3.5,15)")
    p.add_argument("--host", help="address the Ice interfaces bind (default 127.0.0.1); any other needs --certs "
                                  "(or --insecure)")
    p.add_argument("--certs", metavar="DIR", help="serve Ice over TLS on --host, clients need a certificate from DIR "
                                                  "(python -m driver certs DIR); plain TCP stays on 127.0.0.1")
    p.add_argument("--insecure", action="store_true",
                   help="allow plain TCP/UDP off loopback: anyone on that network can fly the drone")
    p.add_argument("--allow-emergency-disarm", action="store_true",
                   help="let an Ice client stop the motors in flight (Vehicle.emergencyStop)")
    p.add_argument("--one-port", nargs="?", type=port, const=9000, metavar="PORT",
                   help="serve every interface on one port, JdeRobot's Gazebo style (default 9000)")
    fleet = p.add_argument_group("fleet (docs/fleet.md)")
    fleet.add_argument("--registry", metavar="HOST:PORT", type=registry,
                       help="register with a lab's IceGrid registry (python -m driver registry) and publish "
                            "telemetry on its IceStorm; every interface is then reached as Pose3D@NAME")
    fleet.add_argument("--name", help="the vehicle's name in the registry (its adapter id and IceStorm topic; "
                                      "default: sim with --sim, else the --aircraft name)")
    fleet.add_argument("--count", type=whole(1, 50), default=1, metavar="N",
                       help="with --sim: N simulated vehicles, each with its server, named NAME-1 to NAME-N "
                            "(system ids 1 to N, homes 10 m apart); the console is off")
    p.add_argument("-v", "--verbose", action="count", default=0, help="more logging (-vv for debug)")
    return p


def log_path(opts, name: str = "") -> str | None:
    """The telemetry log; in a fleet of several each vehicle has its own (mav-sim-2.tlog)."""
    if opts.no_log:
        return None
    logfile = opts.logfile
    if name:
        stem, ext = os.path.splitext(logfile)
        logfile = f"{stem}-{name}{ext}"
    if opts.aircraft and not os.path.isabs(logfile):
        os.makedirs(os.path.join(opts.aircraft, "logs"), exist_ok=True)
        return os.path.join(opts.aircraft, "logs", logfile)
    return logfile


def fleet_names(opts) -> list[str]:
    """The vehicles' names in the registry ([""] without one): NAME, or NAME-1..NAME-N with --count."""
    if not opts.registry:
        return [""] * opts.count
    name = opts.name or ("sim" if opts.sim else opts.aircraft or "")
    return [name] if opts.count == 1 else [f"{name}-{i + 1}" for i in range(opts.count)]


def main(argv: list[str] | None = None) -> int:
    import Ice

    from .ice.server import IceServer, ServeError, check_exposure, default_endpoints, default_properties, ice_problem

    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] == ["certs"]:
        from .ice.certs import main as certs_main
        return certs_main(args[1:], prog=f"{command_name()} certs")
    if args[:1] == ["registry"]:
        from .ice.lab import main as lab_main
        return lab_main(args[1:], prog=f"{command_name()} registry")
    p = parser()
    try:
        props = default_properties(args)             # removes --Ice.* and --MAVLinkServer.* options
    except Ice.LocalException as exc:                # --Ice.Config=/missing.cfg, ...
        p.error(f"cannot read the Ice configuration {ice_problem(exc)}")
    opts = p.parse_args(args)
    signing, allowed = link_security(opts, p)
    try:
        thresholds = battery_thresholds(opts.battery_warning, opts.battery_critical)
    except ValueError as exc:
        p.error(f"--battery-warning/--battery-critical: {exc}")
    if opts.count > 1 and not opts.sim:
        p.error("--count needs --sim (a real vehicle has one server each: start one per companion computer)")
    if opts.count > 1 and not opts.registry:
        p.error("--count needs --registry (the vehicles are told apart by name: python -m driver registry)")
    if opts.registry:
        from .ice.registry import locator, registry_address, vehicle_name_problem
        names = fleet_names(opts)
        problem = "--name is needed with --registry (or --aircraft)" if not names[0] else vehicle_name_problem(names[0])
        if problem:
            p.error(problem)
        host, reg_port = registry_address(opts.registry)
        if not props.getProperty("Ice.Default.Locator"):        # with --certs the lab's registry speaks TLS
            props.setProperty("Ice.Default.Locator", locator(host, reg_port, secure=bool(opts.certs)))
        if opts.count > 1 and opts.one_port is not None:
            p.error("--one-port with --count: the vehicles would share one port; leave it out (the registry "
                    "tells clients each one's port)")
    level = logging.DEBUG if opts.verbose > 1 else logging.INFO if (opts.verbose or opts.daemon) else logging.WARNING
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s")

    from .vehicle.api import Limits
    from .console.console import Console, run_commands, show_logs, wait_for_vehicle
    from .vehicle import Vehicle, VehicleConfig
    from .vehicle.rules import takeoff_altitude_problem

    if opts.host:
        props.setProperty("MAVLinkServer.Host", opts.host)
    for key, on in (("Certs", opts.certs), ("Insecure", opts.insecure and "1"),
                    ("AllowEmergencyDisarm", opts.allow_emergency_disarm and "1")):
        if on:
            props.setProperty("MAVLinkServer." + key, on)
    try:                                             # refused before the vehicle or the simulator starts
        if opts.one_port is not None:
            props.setProperty("MAVLinkServer.Endpoints", default_endpoints(props, opts.one_port))
        check_exposure(props)
    except ServeError as exc:
        print(exc, file=sys.stderr)
        return 1
    if opts.takeoff_alt is not None:
        props.setProperty("MAVLinkServer.TakeoffAltitude", str(opts.takeoff_alt))
    text = props.getPropertyWithDefault("MAVLinkServer.TakeoffAltitude", str(VehicleConfig.takeoff_altitude))
    takeoff_alt = as_float(text)
    problem = takeoff_altitude_problem(takeoff_alt)
    if problem:                                      # from --Ice.Config or --MAVLinkServer.TakeoffAltitude
        p.error(f"MAVLinkServer.TakeoffAltitude={text}: {problem}")
    for i, uri in enumerate(opts.camera):                # MAVLinkServer.Camera.Uri, Uri.2, ...
        props.setProperty("MAVLinkServer.Camera.Uri" + (f".{i + 1}" if i else ""), uri)
    if opts.sim and not props.getProperty("MAVLinkServer.Camera.Uri"):
        props.setProperty("MAVLinkServer.Camera.Uri", "sim")

    _stop_on_sigterm()
    names = fleet_names(opts)
    sims, vehicles, servers = [], [], []
    try:
        masters = [opts.master] * len(names)
        if opts.sim:
            from .sim import SimConfig, SimVehicle
            from .sim.fleet import fleet_configs
            base = SimConfig(tcp_port=0, speedup=opts.sim_speedup, ready_after=opts.sim_ready_after,
                             signing_key=signing.key if signing else None)
            for i, config in enumerate(fleet_configs(len(names), base)):
                sims.append(SimVehicle(config).start())
                masters[i] = masters[i] or f"tcp:127.0.0.1:{sims[-1].tcp_port}"
        for name, master in zip(names, masters):
            master = master or SOLO_MASTER
            vehicle = Vehicle(VehicleConfig(
                connection=master, baud=opts.baudrate, source_system=opts.source_system,
                source_component=opts.source_component, target_system=opts.target_system,
                target_component=opts.target_component, stream_rate=opts.streamrate, takeoff_altitude=takeoff_alt,
                limits=Limits(), tlog_path=log_path(opts, name if len(names) > 1 else ""),
                tlog_append=opts.append_log, outputs=tuple(opts.out), signing=signing, allowed_senders=allowed,
                mavlink_version=1 if opts.mav10 else 2 if opts.mav20 else None, battery_thresholds=thresholds,
                param_metadata=opts.param_metadata))
            vehicles.append(vehicle)
            vehicle.start()
            own = props.clone()
            if name:
                own.setProperty("MAVLinkServer.Name", name)
            try:
                servers.append(IceServer(vehicle, own).start())
            except ServeError as exc:                # port in use, bad endpoint string, unknown host, no registry
                sys.stderr.write(f"{exc}\n")    # one write: the simulator's log lines (other threads) never split it
                return 1
        vehicle, server, master = vehicles[0], servers[0], masters[0] or SOLO_MASTER
        console = Console(vehicle, name=opts.aircraft or names[0])
        daemon = opts.daemon or len(names) > 1
        if not daemon:                               # logs through the console: on a fresh line, each once
            show_logs(console, level)
        for name, server, master in zip(names, servers, masters):
            console.say(f"MAVLink master {master}" + (f" ({name})" if name else ""))
            for s in server.served.values():
                console.say(f"serving {s.name:8} {s.proxy}" +
                            (f"  ({server.indirect_proxy(s.name)})" if server.name else ""))
        if opts.cmd:
            wait_for_vehicle(console)
        for text in opts.cmd:
            run_commands(console, text)
        if daemon:
            _wait_for_signal()
        else:
            _console_loop(console)
    except (KeyboardInterrupt, Terminated):          # Ctrl-C or SIGTERM: stop cleanly, as exit does
        pass
    finally:
        _default_sigterm()                           # a SIGTERM during the clean-up ends the process at once
        for server in servers:
            server.close()
        for vehicle in vehicles:
            vehicle.close()
        for sim in sims:
            sim.stop()
    return 0


def _console_loop(console) -> None:
    try:
        import readline  # (history and line editing for input())
    except ImportError:
        readline = None
    if readline is not None and sys.stdin.isatty() and sys.stdout.isatty():
        console.redraw_input(readline)
    console.watch_messages()
    try:
        console.cmdloop()
    except (KeyboardInterrupt, Terminated):
        console.say("")                              # off the prompt line
        raise
    finally:
        console.redraw_input(None)
        console.stop_watching()


class Terminated(Exception):
    """SIGTERM arrived: the server stops as if told to exit."""


def _stop_on_sigterm() -> None:
    """SIGTERM raises :class:`Terminated` in the main thread, so the vehicle, Ice and the sim are closed;
    a second SIGTERM during that clean-up ends the process at once."""
    def terminate(*_) -> None:
        _default_sigterm()
        raise Terminated()
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, terminate)


def _default_sigterm() -> None:
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _wait_for_signal() -> None:
    """--daemon: run until Ctrl-C or SIGTERM (each raises here)."""
    while True:
        time.sleep(3600)


if __name__ == "__main__":
    sys.exit(main())

"""UavViewerPy: fly a MAVLink drone (3DR Solo, ArduCopter SITL, the built-in simulator) from a laptop.

    uavviewer --sim                          # the built-in simulated ArduCopter, in this process
    uavviewer                                # the last connection used, first a 3DR Solo on udpin:0.0.0.0:14550
    uavviewer --connect tcp:127.0.0.1:5760
    uavviewer --replay flight.tlog           # watch a recorded flight
    uavviewer --ice config/viewer.cfg        # fly through a MAVLinkServer (mavlinkserver) over Ice
    uavviewer --registry 127.0.0.1:4061      # a lab's fleet: every vehicle registered there (docs/fleet.md)
    uavviewer --install-desktop              # put UavViewerPy in the desktop's application menu

(``uavviewer`` once installed with pip; ``python main.py`` or ``python -m uavviewer`` in a checkout.)
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
import time
from pathlib import Path

from driver import options
from driver.sim import DEMO_READY_AFTER
from driver.version import __version__
from uavviewer.connect.choice import sim_name
from uavviewer.settings import TAKEOFF_ALTITUDE_RANGE

SOLO_CONNECTION = "udpin:0.0.0.0:14550"
#: --takeoff-altitude: the range Preferences allow
TAKEOFF_ALTITUDE = options.number(*TAKEOFF_ALTITUDE_RANGE,
                                  "a takeoff altitude is {:g} to {:g} m".format(*TAKEOFF_ALTITUDE_RANGE))


def choose_connection(args: argparse.Namespace, remembered: str) -> str:
    """--connect, else the last connection remembered (if it still reads as one), else a Solo (for runs
    with no --sim/--replay/--ice)."""
    from driver.link.connection import connection_problem
    if args.connect:
        return args.connect
    if remembered and connection_problem(remembered) is None:
        return remembered
    return SOLO_CONNECTION


def open_fleet(args: argparse.Namespace, certs: str | None, wait: float = 30.0, stop: list | None = None):
    """``(fleet, first vehicle's name)`` from --registry, waiting (in the terminal, before any window) until the
    registry lists a vehicle; SystemExit with the reason if it never does, or at once on Ctrl+C (``stop``)."""
    from driver.ice.fleet import IceFleet
    fleet = IceFleet(args.registry, certs).start()
    deadline = time.monotonic() + wait
    said = False
    while True:
        if stop:
            fleet.close()
            raise SystemExit(130)
        names = fleet.names()
        if args.vehicle and args.vehicle in names or not args.vehicle and names:
            return fleet, args.vehicle or names[0]
        if time.monotonic() > deadline:
            fleet.close()
            wanted = f"vehicle {args.vehicle}" if args.vehicle else "any vehicle"
            build_parser().error(f"the registry {args.registry} lists no {wanted} after {wait:g} s"
                                 + (f" ({fleet.problem})" if fleet.problem else "")
                                 + f": start one with python -m driver --sim --registry {args.registry} --name NAME")
        if not said:
            said = True
            print(f"{build_parser().prog}: waiting for vehicles at {args.registry}...", file=sys.stderr, flush=True)
        time.sleep(0.2)


def build_parser() -> argparse.ArgumentParser:
    """The options, named after the command the pilot typed (main.py, uavviewer, python -m uavviewer)."""
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    desktop = p.add_mutually_exclusive_group()
    desktop.add_argument("--install-desktop", action="store_true",
                         help="add UavViewerPy to the desktop's application menu (a freedesktop .desktop entry and "
                              "icon in the per-user data folder, starting this installation) and exit")
    desktop.add_argument("--remove-desktop", action="store_true", help="take that menu entry away again and exit")
    link = p.add_argument_group("vehicle (pick one; default: the last connection used, the first time a "
                                "3DR Solo on " + SOLO_CONNECTION + ")")
    source = link.add_mutually_exclusive_group()
    source.add_argument("--sim", action="store_true",
                        help="start the built-in simulated ArduCopter in this process and fly it")
    source.add_argument("--connect", metavar="STRING", type=options.connection,
                        help="any MAVLink connection string: udpin:HOST:PORT, udpout:HOST:PORT, "
                             "tcp:HOST:PORT, /dev/ttyUSB0 (serial, see --baud), ...; once a vehicle answers on it, "
                             "remembered for the next run without a vehicle option")
    source.add_argument("--replay", metavar="FILE.tlog", type=Path,
                        help="replay a recorded telemetry log instead of flying")
    source.add_argument("--ice", metavar="CONFIG", type=Path,
                        help="fly through a MAVLinkServer (python -m driver) over ZeroC Ice; proxies from an "
                             "Ice config with UAVViewer.<Interface>.Proxy keys (see config/viewer.cfg)")
    source.add_argument("--ice-host", metavar="HOST",
                        help="fly through a MAVLinkServer over ZeroC Ice at HOST, on the default ports")
    source.add_argument("--registry", metavar="HOST:PORT", type=options.registry,
                        help="a lab's fleet: list the vehicles registered with this IceGrid registry (python -m "
                             "driver registry) and fly the one picked in the Fleet panel")
    link.add_argument("--vehicle", metavar="NAME", help="with --registry: the vehicle to fly first (default: the "
                                                        "first listed)")
    link.add_argument("--ice-certs", metavar="DIR", type=Path,
                      help="with --ice/--ice-host/--registry: connect over TLS with the pilot's certificate from DIR "
                           "(made by python -m driver certs DIR); the server's is checked against DIR's CA and the host")
    link.add_argument("--baud", type=options.whole(1, 10_000_000), default=57600, help="serial baud rate (default: %(default)s)")
    options.add_link_security(p.add_argument_group("link security (docs/security.md)"))
    flight = p.add_argument_group("flight")
    flight.add_argument("--takeoff-altitude", type=TAKEOFF_ALTITUDE, default=None, metavar="M",
                        help=f"takeoff altitude above home for this run, {TAKEOFF_ALTITUDE_RANGE[0]:g} to "
                             f"{TAKEOFF_ALTITUDE_RANGE[1]:g} m (default: the one set in Preferences, first 3.0; "
                             "never saved)")
    sim = p.add_argument_group("simulator (with --sim)")
    sim.add_argument("--speedup", type=options.positive, default=1.0,
                     help="simulated time runs this many times faster than real time (default: %(default)s)")
    sim.add_argument("--ready-after", type=options.not_negative, default=DEMO_READY_AFTER, metavar="S",
                     help="seconds until the simulated vehicle has GPS/EKF and is ready to arm "
                          "(default: %(default)s)")
    video = p.add_argument_group("camera")
    video.add_argument("--camera", action="append", default=[], metavar="URI",
                       help="video source, repeatable (Switch camera moves to the next): 0, /dev/video0, clip.mp4, "
                            "rtsp://..., udp://0.0.0.0:5600, stream.sdp, solo, 'ice:Camera:default -h HOST -p 9999', "
                            "sim (default with --sim; see docs/camera.md); overrides the cameras saved in "
                            "Preferences for this run")
    misc = p.add_argument_group("logging")
    misc.add_argument("--log-dir", type=Path, default=None, metavar="DIR",
                      help="where every session records its MAVLink as flight-<time>.tlog, with the viewer's "
                           "log (default: the per-user data folder, e.g. ~/.local/share/UavViewerPy/logs)")
    misc.add_argument("--no-log", action="store_true", help="record no flight log this session")
    misc.add_argument("-v", "--verbose", action="count", default=0,
                      help="more log output (-v info, -vv debug)")
    # Hidden: for documentation screenshots.
    p.add_argument("--screenshot", type=Path, help=argparse.SUPPRESS)
    p.add_argument("--screenshot-after", type=float, default=20.0, help=argparse.SUPPRESS)
    p.add_argument("--screenshot-fly", action="store_true", help=argparse.SUPPRESS)
    return p


def _setup_logging(verbose: int, log_dir: Path | None) -> None:
    level = logging.WARNING if verbose == 0 else logging.INFO if verbose == 1 else logging.DEBUG
    handlers: list[logging.Handler] = [logging.StreamHandler()]
    if log_dir is not None:
        try:
            log_dir.mkdir(parents=True, exist_ok=True)
            handlers.append(logging.FileHandler(log_dir / "viewer.log"))
        except OSError as exc:
            build_parser().error(f"--log-dir {log_dir}: {exc.strerror or exc} (or --no-log to record nothing)")
    logging.basicConfig(level=level, handlers=handlers,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.ice_certs and args.ice is None and args.ice_host is None and args.registry is None:
        build_parser().error("--ice-certs needs --ice, --ice-host or --registry")
    if args.vehicle and args.registry is None:
        build_parser().error("--vehicle needs --registry")
    if args.install_desktop or args.remove_desktop:
        from uavviewer.window import desktop
        done = desktop.install() if args.install_desktop else desktop.remove()
        for line in done:
            print(line)
        return 0
    if args.no_log:
        args.log_dir = None
    elif args.log_dir is None:
        from uavviewer.replay.logs_folder import default_log_dir
        args.log_dir = default_log_dir()
    _setup_logging(args.verbose, args.log_dir)
    # Ctrl+C or kill while the driver and the window are still starting: remembered, and the window closes
    # through its own close path as soon as it exists (a signal's default action would skip it)
    stop_requested = []
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, lambda *_: stop_requested.append(True))
    from PyQt5.QtCore import QTimer
    from PyQt5.QtGui import QIcon
    from PyQt5.QtWidgets import QApplication

    from driver.vehicle import Vehicle, VehicleConfig
    from uavviewer import RESOURCES
    from uavviewer.window.desktop import APP_ID
    from uavviewer.main_window import MainWindow, load_style
    from uavviewer.settings import default_qsettings, load_settings

    signing, allowed = options.link_security(args, build_parser())
    saved = load_settings(default_qsettings())                    # read once: what Preferences keep
    saved_key = saved.signing_key_file
    if signing is None and saved_key:                             # Preferences › Link security's key file
        from driver.link.signing import SigningConfig, read_key_file
        try:
            signing = SigningConfig(key=read_key_file(saved_key))
        except ValueError as exc:
            print(f"{build_parser().prog}: not signing: {exc}", file=sys.stderr)
    sim = None
    if args.sim:
        from driver.sim import SimConfig, SimVehicle
        sim = SimVehicle(SimConfig(tcp_port=0, speedup=args.speedup, ready_after=args.ready_after, camera=True,
                                   signing_key=signing.key if signing else None))   # a vehicle that has our key
        sim.start()
        connection = f"tcp:127.0.0.1:{sim.tcp_port}"
    elif args.replay is not None:
        if not args.replay.is_file():
            build_parser().error(f"no such file: {args.replay}")
        connection = str(args.replay)
    else:
        connection = choose_connection(args, saved.last_connection)
    tlog = None
    if args.log_dir is not None and args.replay is None:
        tlog = str(args.log_dir / time.strftime("flight-%Y%m%d-%H%M%S.tlog"))
    config = VehicleConfig(connection=connection, baud=args.baud, tlog_path=tlog, signing=signing,
                           allowed_senders=allowed,
                           takeoff_altitude=args.takeoff_altitude or saved.takeoff_altitude)
    remote = args.ice is not None or args.ice_host is not None
    fleet = None
    if args.registry is not None:                                 # a lab's fleet: the first vehicle, then the picked
        try:
            fleet, first = open_fleet(args, str(args.ice_certs) if args.ice_certs else None, stop=stop_requested)
        except Exception as exc:                                  # no certificates there, IceSSL refused them
            build_parser().error(f"cannot reach the registry: {' '.join(str(exc).split())}")
        drone = fleet.drone(first)
    elif remote:                                                  # the same window, through the Ice client
        from driver.ice.client import IceDrone
        if args.ice is not None and not args.ice.is_file():
            build_parser().error(f"no such file: {args.ice}")
        certs = str(args.ice_certs) if args.ice_certs else None
        try:
            drone = IceDrone.from_config(str(args.ice) if args.ice else None, host=args.ice_host, certs=certs).start()
        except Exception as exc:                                  # no certificates there, IceSSL refused them
            build_parser().error(f"cannot start the Ice client: {' '.join(str(exc).split())}")
    else:
        drone = Vehicle(config).start()

    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("UavViewerPy")
    app.setApplicationVersion(__version__)
    app.setDesktopFileName(APP_ID)                                # the menu entry's window, for the task bar
    app.setWindowIcon(QIcon(str(RESOURCES / "icons" / "app.svg")))
    app.setStyleSheet(load_style())
    own_camera = ["sim"] if args.sim else []                      # used when Preferences name no camera
    camera_props = None
    if fleet is not None:                                         # the picked vehicle's camera, through the registry
        from driver.ice.client import fleet_properties
        from uavviewer.fleet.controller import FleetController
        camera_props = fleet_properties(args.registry, str(args.ice_certs) if args.ice_certs else None)
        own_camera = [FleetController.camera_uri(first)]
    if remote:                                                    # the server's camera, from the viewer's config
        from driver.ice.client import viewer_properties
        camera_props = viewer_properties(str(args.ice) if args.ice else None, args.ice_host, certs=certs)
        proxy = camera_props.getProperty("UAVViewer.Camera.Proxy")
        own_camera = [f"ice:{proxy}"] if proxy else []
    if camera_props is not None:                    # its camera over TLS too, with the pilot's certificate; in a
        from driver.ice import camera_source as ice_source        # fleet, found through the registry
        ice_source.use_client_properties(camera_props)
    window = MainWindow(drone, takeoff_altitude=args.takeoff_altitude, cameras=args.camera,  # --camera: this run
                        default_cameras=own_camera)
    if sim is not None:                                           # not a raw tcp:127.0.0.1:port in the title
        window.name_vehicle(sim_name(sim.config.speedup))
    if fleet is not None:
        controller = FleetController(fleet, first, parent=window)
        window.fleet_dock.attach(controller)
    connections = window.connections                              # File › Connect switches from this one
    connections.base, connections.speedup = config, args.speedup
    connections.log_dir = str(args.log_dir) if args.log_dir is not None else None
    connections.certs = str(args.ice_certs) if args.ice_certs else None
    from uavviewer.connect.choice import from_command_line
    connections.adopt(drone, from_command_line(args, connection), sim=sim, fleet=fleet,
                      first=first if fleet is not None else "")
    sim = None                                                    # stopped with its drone, whenever that is
    window.show()
    for number in (signal.SIGINT, signal.SIGTERM):              # Ctrl+C, kill: close cleanly, without asking
        signal.signal(number, lambda *_: window.quit_without_asking())
    if stop_requested:
        QTimer.singleShot(0, window.quit_without_asking)
    wake = QTimer()                                               # let Python see the signal
    wake.timeout.connect(lambda: None)
    wake.start(200)
    if args.screenshot is not None:
        _schedule_screenshot(window, args.screenshot, args.screenshot_after, args.screenshot_fly)
    try:
        return app.exec_()
    finally:
        if getattr(window, "fleet", None) is not None:           # the fleet flown last (File › Connect may have
            window.fleet.stop()                                   # left the first one)
        window.connections.close()                                # the vehicle (or fleet) flown last, and any left
        if sim is not None:
            sim.stop()


def _schedule_screenshot(window, path: Path, after: float, fly: bool) -> None:
    """Documentation helper (and the installed form's flight test): optionally take off and fly with both sticks;
    ``after`` seconds later (counted from the first stick push when flying, else from the start) save the window
    and quit."""
    from PyQt5.QtCore import QTimer

    from driver.vehicle.state import SequencePhase

    screen = window.screen().availableGeometry()         # the documentation shows the whole screen (Xvfb: no
    window.setGeometry(screen)                           # window manager, so no title bar to allow for)
    QTimer.singleShot(1000, lambda: window.setGeometry(screen))   # again once the first snapshot is laid out

    def shoot():
        path.parent.mkdir(parents=True, exist_ok=True)
        window.grab().save(str(path))
        window.quit_without_asking()                                  # it is flying: no question

    if not fly:
        QTimer.singleShot(int(after * 1000), shoot)
        return

    def takeoff_when_ready():
        s = window.adapter.state
        if s.readiness.ready_to_arm:
            window.adapter.send(window.adapter.drone.takeoff, window.takeoff_altitude)
        else:
            QTimer.singleShot(500, takeoff_when_ready)
    QTimer.singleShot(1000, takeoff_when_ready)

    pushed = []

    def push_stick():
        s = window.adapter.state
        if s.takeoff.phase is SequencePhase.DONE and s.can_fly_velocity:
            window.rightStick.hold(0.25, 0.75)                  # as if the pilot held it
            window.leftStick.hold(0.35, 0.0)
            if not pushed:
                pushed.append(True)
                QTimer.singleShot(int(after * 1000), shoot)
        QTimer.singleShot(200, push_stick)
    QTimer.singleShot(1000, push_stick)

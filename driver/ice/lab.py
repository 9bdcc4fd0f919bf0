"""A lab's ZeroC services: Debian's IceGrid registry and IceStorm (in IceBox), started and stopped together.

    python -m driver registry                        # 127.0.0.1:4061, for drones and viewers on this machine
    python -m driver registry --host 10.1.1.5 --certs ~/uav-certs   # a lab machine: TLS, certificate holders only

Configured by ``config/icegrid-registry.cfg`` and ``config/icestorm.cfg``; the host, the port, the data folders
and (with certificates) the IceSSL keys are set here. IceBox's IceStorm registers its TopicManager with the
registry, so servers and observers need only the registry's address.
"""
from __future__ import annotations

import argparse
import glob
import logging
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

import Ice

from . import data_dir, registry
from .problems import ice_problem

log = logging.getLogger(__name__)

CONFIG_DIR = data_dir("config")
REGISTRY_CONFIG = os.path.join(CONFIG_DIR, "icegrid-registry.cfg")
ICESTORM_CONFIG = os.path.join(CONFIG_DIR, "icestorm.cfg")
#: program or library → the Debian package that ships it (3.7.8, like python3-zeroc-ice)
PACKAGES = {"icegridregistry": "zeroc-icegrid", "icebox": "zeroc-icebox", "libIceStormService.so.37": "libzeroc-icestorm3.7"}


class LabError(RuntimeError):
    """A service cannot start, said in one line."""


def missing() -> list[str]:
    """The Debian packages this machine lacks for a lab (empty: everything is there)."""
    absent = [pkg for prog, pkg in PACKAGES.items() if prog.startswith("ice") and shutil.which(prog) is None]
    libs = [p for d in ("/usr/lib", "/usr/lib64", "/usr/local/lib", "/usr/lib/*-linux-gnu", "/usr/local/lib/*-linux-gnu")
            for p in glob.glob(os.path.join(d, "libIceStormService.so.37"))]
    if not libs:
        absent.append(PACKAGES["libIceStormService.so.37"])
    return absent


def _endpoint(host: str, port: int | None, secure: bool) -> str:
    """Plain TCP, or with certificates TLS on ``host`` plus plain TCP on 127.0.0.1 (as the MAVLinkServer)."""
    h = f'"{host}"' if ":" in host else host
    p = f" -p {port}" if port is not None else ""
    if not secure:
        return f"tcp -h {h}{p}"
    ssl = f"ssl -h {h}{p}"
    return ssl if host in ("127.0.0.1", "localhost") else f"{ssl}:tcp -h 127.0.0.1{p}"


class Lab:
    """``icegridregistry`` and ``icebox`` (IceStorm) as child processes; ``start()``, then ``stop()``."""

    def __init__(self, host: str = "127.0.0.1", port: int = registry.DEFAULT_PORT, data: str | None = None,
                 certs: str | None = None, insecure: bool = False, icestorm: bool = True) -> None:
        self.host, self.port, self.certs, self.insecure, self.icestorm = host, port, certs, insecure, icestorm
        self._data, self._own_data = data, data is None
        self._procs: list[subprocess.Popen] = []

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    @property
    def locator(self) -> str:
        """The registry's locator: over TLS with certificates (clients then need one from the same CA)."""
        return registry.locator(self.host, self.port, secure=bool(self.certs))

    def _check_exposure(self) -> None:
        from .server import exposure_problem
        props = Ice.createProperties()
        if self.insecure:
            props.setProperty("MAVLinkServer.Insecure", "1")
        if self.certs:
            for key, value in self._ssl().items():
                props.setProperty(key, value)
        warnings: list[str] = []
        problem = exposure_problem("the IceGrid registry", _endpoint(self.host, self.port, bool(self.certs)), props,
                                   warnings)
        if problem:
            raise LabError(problem.replace("fly the drone", "register a fake drone or reach the real ones"))
        for text in warnings:
            log.warning("%s", text)

    def _ssl(self) -> dict[str, str]:
        from .certs import CertError, ssl_properties
        try:
            return ssl_properties(self.certs, "server")
        except CertError as exc:
            raise LabError(str(exc)) from None

    def start(self, timeout: float = 10.0) -> "Lab":
        absent = missing()
        if absent:
            raise LabError(f"ZeroC's services are not installed: apt-get install {' '.join(absent)} "
                           "(scripts/bootstrap does)")
        self._check_exposure()
        if self._data is None:
            self._data = tempfile.mkdtemp(prefix="uav-lab-")
        secure = bool(self.certs)
        configs = [REGISTRY_CONFIG]
        if secure:                               # the key's password goes in a 0600 file, never on a command line
            from ..core.files import private_dir, write_private
            private_dir(self._data)
            text = "".join(f"{k}={v}\n" for k, v in self._ssl().items())
            configs.append(write_private(os.path.join(self._data, "icessl.cfg"), text.encode()))
        reg_dir = os.path.join(self._data, "registry")
        os.makedirs(reg_dir, mode=0o700, exist_ok=True)
        try:
            self._spawn(["icegridregistry", f"--Ice.Config={','.join(configs)}",
                         f"--IceGrid.Registry.Client.Endpoints={_endpoint(self.host, self.port, secure)}",
                         f"--IceGrid.Registry.Server.Endpoints={_endpoint(self.host, None, secure)}",
                         f"--IceGrid.Registry.LMDB.Path={reg_dir}"], "registry")
            probe = [f"--Ice.Default.Locator={self.locator}", "--Ice.Default.InvocationTimeout=1000",
                     "--Ice.Default.Timeout=1000"] + [f"--{k}={v}" for k, v in
                                                                   (self._ssl().items() if secure else ())]
            com = Ice.initialize(probe)                  # (in this process: the password stays off command lines)
            try:
                self._wait(lambda: com.getDefaultLocator().ice_ping(), "the IceGrid registry", timeout)
                if self.icestorm:
                    storm_dir = os.path.join(self._data, "icestorm")
                    os.makedirs(storm_dir, mode=0o700, exist_ok=True)
                    host = self.host
                    self._spawn(["icebox", f"--Ice.Config={','.join([ICESTORM_CONFIG] + configs[1:])}",
                                 f"--Ice.Default.Locator={self.locator}",
                                 f"--IceStorm.TopicManager.Endpoints={_endpoint(host, None, secure)}",
                                 f"--IceStorm.Publish.Endpoints={_endpoint(host, None, secure)}",
                                 f"--IceStorm.LMDB.Path={storm_dir}"], "IceStorm")
                    self._wait(lambda: com.stringToProxy(registry.TOPIC_MANAGER).ice_ping(), "IceStorm", timeout)
            finally:
                com.destroy()
        except BaseException:
            self.stop()
            raise
        return self

    def _spawn(self, argv: list[str], what: str) -> None:
        """A service whose warnings go to ``<data>/<what>.log`` (a pipe nobody reads would fill up and stop it)."""
        log_path = os.path.join(self._data, f"{what}.log")
        setpriv = shutil.which("setpriv")          # util-linux: the service ends with us, even if we are killed
        if setpriv and threading.current_thread() is threading.main_thread():   # (the signal follows the thread)
            argv = [setpriv, "--pdeathsig", "TERM", "--", *argv]
        with open(log_path, "ab") as out:
            proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                                    start_new_session=True)
        proc.what, proc.log = what, log_path
        self._procs.append(proc)

    def _wait(self, ping, what: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while True:
            try:
                ping()
                return
            except Ice.LocalException as exc:
                self._check_exited()
                if time.monotonic() > deadline:
                    raise LabError(f"{what} did not answer within {timeout:g} s: {ice_problem(exc)}") from None
            time.sleep(0.05)

    def _check_exited(self) -> None:
        """LabError with its last words if a service has exited (its port taken, a bad configuration)."""
        for proc in self._procs:
            if proc.poll() is not None:
                with open(proc.log, errors="replace") as f:
                    said = " ".join(f.read().split())[-400:]
                raise LabError(f"{proc.what} exited ({proc.returncode}): {said or 'no message'}")

    def stop(self) -> None:
        """IceStorm first (its subscribers), then the registry; the data folder goes if it was ours."""
        for proc in reversed(self._procs):
            if proc.poll() is None:
                proc.terminate()
                try:
                    proc.wait(5)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        self._procs.clear()
        if self._own_data and self._data is not None:
            shutil.rmtree(self._data, ignore_errors=True)
            self._data = None

    def logs(self) -> list[str]:
        """Where each service writes its warnings."""
        return [p.log for p in self._procs]

    def running(self) -> bool:
        return bool(self._procs) and all(p.poll() is None for p in self._procs)

    def __enter__(self) -> "Lab":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


def main(argv: list[str], prog: str = "python -m driver registry") -> int:
    """``python -m driver registry``: run the lab's registry and IceStorm until Ctrl-C or SIGTERM."""
    p = argparse.ArgumentParser(prog=prog,
                                description="Run a lab's IceGrid registry and IceStorm (ZeroC's, from Debian): "
                                            "MAVLinkServers register there (--registry HOST:PORT --name NAME), "
                                            "viewers list and fly them (main.py --registry HOST:PORT).")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to serve (default 127.0.0.1); any other needs --certs (or --insecure)")
    p.add_argument("--port", type=int, default=registry.DEFAULT_PORT, help="the registry's port (default 4061)")
    p.add_argument("--data", metavar="DIR", help="keep the registry's and IceStorm's databases here (default: a "
                                                 "temporary folder, removed at exit)")
    p.add_argument("--certs", metavar="DIR", help="TLS with client certificates from DIR (python -m driver certs)")
    p.add_argument("--insecure", action="store_true", help="allow plain TCP off loopback")
    p.add_argument("--no-icestorm", action="store_true", help="only the registry")
    opts = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    lab = Lab(opts.host, opts.port, opts.data, opts.certs, opts.insecure, icestorm=not opts.no_icestorm)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))   # before the line that says it is up: whoever
    try:                                                        # reads it may stop it at once, and cleanly
        lab.start()
    except LabError as exc:
        print(exc, file=sys.stderr)
        return 1
    print(f"IceGrid registry on {lab.address}" + (" with IceStorm" if lab.icestorm else "") +
          f"; servers: python -m driver --registry {lab.address} --name NAME; "
          f"viewers: python main.py --registry {lab.address}; their logs: {', '.join(lab.logs())}", flush=True)
    try:
        while not stop and lab.running():
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        failed = not lab.running()
        lab.stop()
    if failed and not stop:
        print("a service stopped by itself", file=sys.stderr)
        return 1
    return 0

"""File › Connect: pick a link (UDP, TCP, serial, the built-in simulator, an Ice server, a lab's registry) or a
recent one."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import (
    QComboBox, QDialog, QDialogButtonBox, QFileDialog, QFormLayout, QHBoxLayout, QLabel, QLineEdit, QListWidget,
    QListWidgetItem, QPushButton, QSpinBox, QStackedWidget, QVBoxLayout, QWidget,
)

from .choice import SITL_TCP, Choice, Kind, serial_ports

__all__ = ["ConnectDialog", "KINDS"]

KINDS = ("UDP", "TCP", "Serial", "Simulated vehicle", "Ice server", "Lab registry")
BAUDS = (57600, 115200, 921600, 38400, 9600)


def _port_box(value: int) -> QSpinBox:
    box = QSpinBox()
    box.setRange(1, 65535)
    box.setValue(value)
    return box


class ConnectDialog(QDialog):
    """Not modal: the window flies on behind it. ``chosenConnection`` carries the pilot's :class:`Choice`; the
    dialog stays open while the link is tried (:meth:`set_busy`), says why it failed (:meth:`show_problem`) where
    the pilot asked, and is closed by its owner once a vehicle answers."""

    chosenConnection = pyqtSignal(object)

    def __init__(self, recent: list[Choice], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("connectDialog")
        self.setWindowTitle("Connect to a vehicle")
        self.recent_list = QListWidget()
        self.recent_list.setObjectName("recentConnections")
        self.recent_list.setMaximumHeight(110)
        for choice in recent:
            item = QListWidgetItem(choice.label)
            item.setData(Qt.UserRole, choice)
            self.recent_list.addItem(item)
        self.kind = QComboBox()
        self.kind.addItems(KINDS)
        self.pages = QStackedWidget()
        # UDP: listen where a vehicle sends (the Solo, a telemetry radio bridge), or send to one
        self.udp_mode = QComboBox()
        self.udp_mode.addItem("Listen (udpin)", "udpin")
        self.udp_mode.addItem("Send to (udpout)", "udpout")
        self.udp_host = QLineEdit("0.0.0.0")
        self.udp_port = _port_box(14550)
        self.pages.addWidget(self._form(("Direction", self.udp_mode), ("Address", self.udp_host),
                                        ("Port", self.udp_port)))
        # TCP, with ArduPilot SITL's port as a preset
        self.tcp_host = QLineEdit("127.0.0.1")
        self.tcp_port = _port_box(5760)
        self.sitl_button = QPushButton("ArduPilot SITL (127.0.0.1:5760)")
        self.sitl_button.setObjectName("sitlPreset")
        self.sitl_button.clicked.connect(self._sitl)
        self.pages.addWidget(self._form(("Host", self.tcp_host), ("Port", self.tcp_port), ("Preset", self.sitl_button)))
        # serial: the ports the system lists now (pyserial through mavutil), or one typed in
        self.serial_port = QComboBox()
        self.serial_port.setEditable(True)
        self.serial_refresh = QPushButton("Refresh")
        self.serial_refresh.clicked.connect(self.refresh_ports)
        row = QWidget()
        line = QHBoxLayout(row)
        line.setContentsMargins(0, 0, 0, 0)
        line.addWidget(self.serial_port, 1)
        line.addWidget(self.serial_refresh)
        self.baud = QComboBox()
        for b in BAUDS:
            self.baud.addItem(str(b), b)
        self.pages.addWidget(self._form(("Port", row), ("Baud", self.baud)))
        sim = QLabel("The built-in simulated ArduCopter, started in this program: real MAVLink over a local TCP "
                     "socket, ready to arm after a few seconds.")
        sim.setWordWrap(True)
        self.pages.addWidget(sim)
        # Ice: a MAVLinkServer's host (default ports), or a viewer config naming its proxies
        self.ice_host = QLineEdit()
        self.ice_host.setPlaceholderText("host, e.g. 10.1.1.10 — or a viewer .cfg")
        browse = QPushButton("Config…")
        browse.clicked.connect(self._browse_ice)
        row = QWidget()
        line = QHBoxLayout(row)
        line.setContentsMargins(0, 0, 0, 0)
        line.addWidget(self.ice_host, 1)
        line.addWidget(browse)
        self.pages.addWidget(self._form(("MAVLinkServer", row)))
        # a lab's IceGrid registry: every vehicle registered there, in the Fleet panel
        self.registry = QLineEdit()
        self.registry.setPlaceholderText("HOST:PORT, e.g. 10.1.1.5:4061")
        self.pages.addWidget(self._form(("Registry", self.registry)))
        self.kind.currentIndexChanged.connect(self.pages.setCurrentIndex)
        self.problem = QLabel()
        self.problem.setObjectName("connectProblem")
        self.problem.setStyleSheet("color: #ff8a80;")
        self.problem.setWordWrap(True)
        self.progress = QLabel()
        self.progress.setObjectName("connectProgress")
        self.progress.setWordWrap(True)
        self.progress.setVisible(False)
        self.buttons = QDialogButtonBox(QDialogButtonBox.Cancel)
        self.connect_button = self.buttons.addButton("Connect", QDialogButtonBox.AcceptRole)
        self.connect_button.setObjectName("connectButton")
        self.buttons.accepted.connect(self._accept)
        self.buttons.rejected.connect(self.reject)
        box = QVBoxLayout(self)
        if recent:
            box.addWidget(QLabel("Recent"))
            box.addWidget(self.recent_list)
        form = QFormLayout()
        form.addRow("Type", self.kind)
        box.addLayout(form)
        box.addWidget(self.pages)
        box.addWidget(self.progress)
        box.addWidget(self.problem)
        box.addWidget(self.buttons)
        self.recent_list.itemClicked.connect(lambda item: self.show_choice(item.data(Qt.UserRole)))
        self.recent_list.itemDoubleClicked.connect(lambda item: (self.show_choice(item.data(Qt.UserRole)),
                                                                 self._accept()))
        self.refresh_ports()
        if recent:
            self.show_choice(recent[0])

    @staticmethod
    def _form(*rows) -> QWidget:
        page = QWidget()
        form = QFormLayout(page)
        form.setContentsMargins(0, 0, 0, 0)
        for label, widget in rows:
            form.addRow(label, widget)
        return page

    def refresh_ports(self) -> None:
        typed = self.serial_port.currentText()
        self.serial_port.clear()
        for device, description in serial_ports():
            self.serial_port.addItem(f"{device}  {description}".strip(), device)
        if typed:
            self.serial_port.setEditText(typed)

    def _sitl(self) -> None:
        self.tcp_host.setText(SITL_TCP.split(":")[1])
        self.tcp_port.setValue(int(SITL_TCP.split(":")[2]))

    def _browse_ice(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Viewer Ice config", "", "Ice config (*.cfg);;All files (*)")
        if path:
            self.ice_host.setText(path)

    def show_choice(self, choice: Choice) -> None:
        """Fill the form with ``choice`` (a recent connection clicked)."""
        if choice.kind is Kind.SIM:
            self.kind.setCurrentIndex(KINDS.index("Simulated vehicle"))
        elif choice.kind is Kind.ICE:
            self.kind.setCurrentIndex(KINDS.index("Ice server"))
            self.ice_host.setText(choice.target)
        elif choice.kind is Kind.REGISTRY:
            self.kind.setCurrentIndex(KINDS.index("Lab registry"))
            self.registry.setText(choice.target)
        elif choice.is_serial:
            self.kind.setCurrentIndex(KINDS.index("Serial"))
            self.serial_port.setEditText(choice.target)
            i = self.baud.findData(choice.baud)
            if i < 0:
                self.baud.addItem(str(choice.baud), choice.baud)
                i = self.baud.count() - 1
            self.baud.setCurrentIndex(i)
        elif choice.kind is Kind.MAVLINK:
            scheme, _, rest = choice.target.partition(":")
            host, _, port = rest.rpartition(":")
            if scheme.lower().startswith("tcp"):
                self.kind.setCurrentIndex(KINDS.index("TCP"))
                self.tcp_host.setText(host)
                self.tcp_port.setValue(int(port) if port.isdigit() else 5760)
            else:
                self.kind.setCurrentIndex(KINDS.index("UDP"))
                self.udp_mode.setCurrentIndex(max(0, self.udp_mode.findData(scheme.lower())))
                self.udp_host.setText(host)
                self.udp_port.setValue(int(port) if port.isdigit() else 14550)

    def chosen(self) -> Choice:
        kind = KINDS[self.kind.currentIndex()]
        if kind == "UDP":
            return Choice(Kind.MAVLINK, f"{self.udp_mode.currentData()}:{self.udp_host.text().strip()}:"
                                        f"{self.udp_port.value()}")
        if kind == "TCP":
            return Choice(Kind.MAVLINK, f"tcp:{self.tcp_host.text().strip()}:{self.tcp_port.value()}")
        if kind == "Serial":
            text = self.serial_port.currentText().strip()
            i = self.serial_port.findText(text)
            device = self.serial_port.itemData(i) if i >= 0 else text.split()[0] if text else ""
            return Choice(Kind.MAVLINK, device, int(self.baud.currentData() or 57600))
        if kind == "Simulated vehicle":
            return Choice(Kind.SIM)
        if kind == "Lab registry":
            return Choice(Kind.REGISTRY, self.registry.text().strip())
        return Choice(Kind.ICE, self.ice_host.text().strip())

    def _accept(self) -> None:
        choice = self.chosen()
        problem = choice.problem()
        if problem:
            self.show_problem(problem)
            return
        self.show_problem("")
        self.chosenConnection.emit(choice)

    def show_problem(self, text: str) -> None:
        self.problem.setText(text)

    def set_busy(self, busy: bool, text: str = "") -> None:
        """A link is being tried (``text`` says which, and for how long): Connect waits until it is decided."""
        self.connect_button.setEnabled(not busy)
        self.progress.setText(text)
        self.progress.setVisible(busy and bool(text))

"""One parameter, to read and change: its meaning, units and bounds from the metadata, and the new value.

It only shows and asks: a value typed here is emitted (``stageRequested``); the page judges it and stages it.
"""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import (
    QComboBox, QFrame, QHBoxLayout, QLabel, QLineEdit, QListWidget, QListWidgetItem, QPushButton, QSizePolicy,
    QVBoxLayout, QWidget,
)

from driver.params.model import Parameter
from driver.params.values import format_value

from .values import meta_attr, parse_value, range_text

__all__ = ["ParamEditor"]


class ParamEditor(QFrame):
    stageRequested = pyqtSignal(str, str)        # name, the value as typed
    revertRequested = pyqtSignal(str)            # name: drop its pending change

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("paramEditor")
        self._name = ""
        self._param: Parameter | None = None
        self.title = QLabel("Pick a parameter")
        self.title.setObjectName("paramTitle")
        self.title.setTextInteractionFlags(Qt.TextSelectableByMouse)
        self.display_name = QLabel()
        self.display_name.setWordWrap(True)
        self.description = QLabel()
        self.description.setWordWrap(True)
        self.description.setObjectName("paramDescription")
        self.description.setAlignment(Qt.AlignTop | Qt.AlignLeft)
        self.facts = QLabel()
        self.facts.setObjectName("paramFacts")
        self.facts.setWordWrap(True)
        self.warning = QLabel()
        self.warning.setObjectName("paramWarning")
        self.warning.setWordWrap(True)
        self.reboot = QLabel("Takes effect after the vehicle reboots")
        self.reboot.setObjectName("paramReboot")
        self.value = QLineEdit()
        self.value.setObjectName("paramValue")
        self.value.setPlaceholderText("new value")
        self.choices = QComboBox()                 # an enumerated parameter's values
        self.choices.setObjectName("paramChoices")
        self.bits = QListWidget()                  # a bitmask parameter's bits
        self.bits.setObjectName("paramBits")
        self.bits.setMaximumHeight(150)
        self.bits.setHorizontalScrollBarPolicy(Qt.ScrollBarAlwaysOff)
        self.bits.setStyleSheet("QListWidget::indicator { width: 12px; height: 12px; border: 1px solid #6b7d91;"
                                " border-radius: 3px; background: #0d1117; }"
                                "QListWidget::indicator:checked { background: #2f81f7; border-color: #8cb8ff; }")
        self.stage_button = QPushButton("Stage change")
        self.stage_button.setObjectName("stageButton")
        self.stage_button.setToolTip("Add this value to the changes to review and write (Enter)")
        self.revert_button = QPushButton("Revert")
        self.revert_button.setToolTip("Drop this parameter's pending change")
        self.error = QLabel()
        self.error.setObjectName("paramError")
        self.error.setWordWrap(True)

        buttons = QHBoxLayout()
        buttons.addWidget(self.stage_button)
        buttons.addWidget(self.revert_button)
        buttons.addStretch(1)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(10, 8, 10, 8)
        for w in (self.title, self.display_name, self.facts, self.warning, self.reboot, self.choices, self.bits,
                  self.value):
            layout.addWidget(w)
        layout.addLayout(buttons)
        layout.addWidget(self.error)
        layout.addWidget(self.description, 1)
        self.description.setSizePolicy(QSizePolicy.Preferred, QSizePolicy.Expanding)

        self.value.returnPressed.connect(self._stage)
        self.stage_button.clicked.connect(self._stage)
        self.revert_button.clicked.connect(lambda: self._name and self.revertRequested.emit(self._name))
        self.choices.activated.connect(self._choice_picked)
        self.bits.itemChanged.connect(self._bit_toggled)
        self.show_parameter(None, None, None)

    @property
    def name(self) -> str:
        return self._name

    def show_parameter(self, param: Parameter | None, meta, pending: float | None, *,
                       have_metadata: bool = False) -> None:
        """Show ``param`` (None: nothing picked) with its metadata and the change pending for it."""
        same = param is not None and param.name == self._name
        self._param = param
        self._name = param.name if param is not None else ""
        enabled = param is not None
        for w in (self.value, self.stage_button, self.revert_button, self.choices, self.bits):
            w.setEnabled(enabled)
        if param is None:
            self.title.setText("Pick a parameter")
            for label in (self.display_name, self.description, self.facts, self.warning, self.error):
                label.setText("")
            for w in (self.reboot, self.choices, self.bits, self.warning):
                w.hide()
            return
        self.title.setText(param.name)
        self.display_name.setText(meta_attr(meta, "display_name", ""))
        self.display_name.setVisible(bool(self.display_name.text()))
        self.description.setText(meta_attr(meta, "description", ""))
        facts = [f"Vehicle: <b>{format_value(param.type, param.value)}</b>"
                 + (f" {meta_attr(meta, 'units')}" if meta_attr(meta, "units") else ""),
                 f"type {param.type.name.lower()}"]
        if range_text(meta):
            facts.append(f"range {range_text(meta)}")
        if meta_attr(meta, "increment") is not None:
            facts.append(f"step {meta_attr(meta, 'increment'):g}")
        if pending is not None:
            facts.append(f"<span style='color:#ffd27a'>pending → {format_value(param.type, pending)}</span>")
        self.facts.setText(" · ".join(facts))
        if meta is None:
            self.warning.setText("No metadata for this parameter: its bounds, units and meaning are unknown here. "
                                 "Check the value against ArduPilot's documentation before writing it."
                                 + ("" if have_metadata else " (Load ArduPilot's apm.pdef.xml with Metadata….)"))
            self.warning.show()
        else:
            self.warning.hide()
        self.reboot.setVisible(bool(meta_attr(meta, "reboot_required", False)))
        self.revert_button.setEnabled(pending is not None)
        shown = pending if pending is not None else param.value
        self._fill_choices(meta, shown)
        self._fill_bits(meta, shown)
        if not same or not self.value.hasFocus():
            self.value.setText(format_value(param.type, shown))
        if not same:
            self.error.setText("")

    def show_error(self, text: str) -> None:
        self.error.setText(text)

    def focus_value(self) -> None:
        self.value.setFocus(Qt.OtherFocusReason)
        self.value.selectAll()

    # -- enumerations and bitmasks write into the value box -------------------------------------
    def _fill_choices(self, meta, shown: float) -> None:
        values = {} if meta_attr(meta, "bitmask", {}) else meta_attr(meta, "values", {})   # bits say more
        self.choices.blockSignals(True)
        self.choices.clear()
        for key, label in values.items():
            self.choices.addItem(f"{float(key):g}: {label}", float(key))
        found = self.choices.findData(float(shown))
        self.choices.setCurrentIndex(found)
        self.choices.blockSignals(False)
        self.choices.setVisible(bool(values))

    def _choice_picked(self, index: int) -> None:
        value = self.choices.itemData(index)
        if value is not None and self._param is not None:
            self.value.setText(format_value(self._param.type, value))

    def _fill_bits(self, meta, shown: float) -> None:
        bits = meta_attr(meta, "bitmask", {})
        self.bits.blockSignals(True)
        self.bits.clear()
        for bit, label in bits.items():
            item = QListWidgetItem(f"{int(bit)}: {label}")
            item.setToolTip(f"bit {int(bit)} (value {1 << int(bit)}): {label}")
            item.setData(Qt.UserRole, int(bit))
            item.setFlags(item.flags() | Qt.ItemIsUserCheckable)
            item.setCheckState(Qt.Checked if int(shown) >> int(bit) & 1 else Qt.Unchecked)
            self.bits.addItem(item)
        self.bits.blockSignals(False)
        self.bits.setVisible(bool(bits))

    def _bit_toggled(self, item: QListWidgetItem) -> None:
        current = parse_value(self.value.text())
        if current is None or self._param is None:
            return
        mask = 1 << item.data(Qt.UserRole)
        value = int(current) | mask if item.checkState() == Qt.Checked else int(current) & ~mask
        self.value.setText(format_value(self._param.type, value))

    def _stage(self) -> None:
        if self._name:
            self.stageRequested.emit(self._name, self.value.text())

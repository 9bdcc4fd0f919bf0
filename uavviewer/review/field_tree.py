"""The log's message types and their fields, searchable: a double click plots a field on the left axis; the
right axis from the context menu."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QLineEdit, QMenu, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

__all__ = ["FieldTree"]


class FieldTree(QWidget):
    fieldChosen = pyqtSignal(str, str, int)          # type, field, axis (0 left, 1 right)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.search = QLineEdit(placeholderText="Search fields (e.g. roll, BAT, vibe)")
        self.search.setClearButtonEnabled(True)
        self.tree = QTreeWidget()
        self.tree.setHeaderLabels(["Message / field", "records"])
        self.tree.setContextMenuPolicy(Qt.CustomContextMenu)
        self.tree.customContextMenuRequested.connect(self._menu)
        self.tree.itemDoubleClicked.connect(lambda item, _c: self._choose(item, 0))
        self.search.textChanged.connect(self.filter)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.search)
        layout.addWidget(self.tree)

    def set_tree(self, tree: dict[str, list[str]], counts: dict[str, int]) -> None:
        self.tree.clear()
        for mtype, fields in tree.items():
            top = QTreeWidgetItem([mtype, f"{counts.get(mtype, 0):,}"])
            for f in fields:
                child = QTreeWidgetItem([f, ""])
                child.setData(0, Qt.UserRole, (mtype, f))
                top.addChild(child)
            self.tree.addTopLevelItem(top)
        self.tree.resizeColumnToContents(0)

    def filter(self, text: str) -> None:
        words = text.lower().split()
        for i in range(self.tree.topLevelItemCount()):
            top = self.tree.topLevelItem(i)
            shown = 0
            for k in range(top.childCount()):
                child = top.child(k)
                name = f"{top.text(0)}.{child.text(0)}".lower()
                hit = all(w in name for w in words)
                child.setHidden(not hit)
                shown += hit
            top.setHidden(shown == 0)
            top.setExpanded(bool(words) and shown > 0)

    def _choose(self, item: QTreeWidgetItem, axis: int) -> None:
        key = item.data(0, Qt.UserRole)
        if key:
            self.fieldChosen.emit(key[0], key[1], axis)

    def _menu(self, point) -> None:
        item = self.tree.itemAt(point)
        if item is None or not item.data(0, Qt.UserRole):
            return
        menu = QMenu(self)
        menu.addAction("Plot on the left axis", lambda: self._choose(item, 0))
        menu.addAction("Plot on the right axis", lambda: self._choose(item, 1))
        menu.exec_(self.tree.viewport().mapToGlobal(point))

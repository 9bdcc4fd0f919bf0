"""Vehicle › Setup: a page list on the left (as QGroundControl's Vehicle Setup, plainer), the page on the right."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import (
    QDialog, QDialogButtonBox, QHBoxLayout, QLabel, QListWidget, QScrollArea, QStackedWidget, QVBoxLayout, QWidget,
)

__all__ = ["SetupDialog"]


class SetupDialog(QDialog):
    pageShown = pyqtSignal(str)                  # the page's title, when the pilot turns to it

    def __init__(self, pages: list[QWidget], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Vehicle setup")
        self.setObjectName("setupDialog")
        self.pages = {page.title: page for page in pages}
        self.list = QListWidget()
        self.list.setObjectName("setupPages")
        self.list.setMaximumWidth(140)
        self.stack = QStackedWidget()
        for page in pages:
            self.list.addItem(page.title)
            scroll = QScrollArea()                   # a small screen scrolls the page, the buttons stay
            scroll.setWidgetResizable(True)
            scroll.setWidget(page)
            scroll.setFrameShape(QScrollArea.NoFrame)
            self.stack.addWidget(scroll)
        self.list.currentRowChanged.connect(self._turn)
        body = QHBoxLayout()
        body.addWidget(self.list)
        body.addWidget(self.stack, 1)
        layout = QVBoxLayout(self)
        self.notice = QLabel("")                     # what this connection cannot do, above every page
        self.notice.setObjectName("setupNotice")
        self.notice.setWordWrap(True)
        self.notice.setStyleSheet("background: #fff3cd; color: #5d4300; padding: 4px")
        self.notice.setVisible(False)
        layout.addWidget(self.notice)
        layout.addLayout(body, 1)
        buttons = QDialogButtonBox(QDialogButtonBox.Close)
        buttons.rejected.connect(self.reject)
        layout.addWidget(buttons)
        self.resize(900, 560)
        self.setWindowFlag(Qt.WindowContextHelpButtonHint, False)
        self.list.setCurrentRow(0)

    def _turn(self, row: int) -> None:
        self.stack.setCurrentIndex(row)
        if row >= 0:
            self.pageShown.emit(self.list.item(row).text())

    def set_notice(self, text: str) -> None:
        if text != self.notice.text():
            self.notice.setText(text)
        self.notice.setVisible(bool(text))

    def turn_to(self, title: str) -> QWidget:
        row = list(self.pages).index(title)
        self.list.setCurrentRow(row)
        return self.pages[title]

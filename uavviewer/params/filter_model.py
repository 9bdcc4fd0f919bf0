"""Which parameters the page lists: a search, a group (prefix), modified only (the model keeps them by name)."""
from __future__ import annotations

from PyQt5.QtCore import QModelIndex, QSortFilterProxyModel

from .table_model import GROUP_ROLE, MODIFIED_ROLE, SEARCH_ROLE

__all__ = ["ParameterFilter"]


class ParameterFilter(QSortFilterProxyModel):
    """Every word of the search must appear in the name, display name or description (``RTL ALT`` finds
    RTL_ALT and RTL_ALT_FINAL; ``failsafe`` finds FS_*)."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self._words: list[str] = []
        self._group = ""
        self._modified_only = False
        self.setDynamicSortFilter(True)           # the model is sorted by name already: nothing to sort here

    def set_search(self, text: str) -> None:
        self._words = text.upper().split()
        self.invalidateFilter()

    def set_group(self, group: str) -> None:
        """"" lists every group."""
        self._group = group
        self.invalidateFilter()

    def set_modified_only(self, on: bool) -> None:
        self._modified_only = on
        self.invalidateFilter()

    @property
    def group(self) -> str:
        return self._group

    def filterAcceptsRow(self, row: int, parent: QModelIndex) -> bool:  # noqa: N802
        index = self.sourceModel().index(row, 0, parent)
        if self._group and index.data(GROUP_ROLE) != self._group:
            return False
        if self._modified_only and not index.data(MODIFIED_ROLE):
            return False
        if self._words:
            text = index.data(SEARCH_ROLE)
            return all(word in text for word in self._words)
        return True

"""One way every bench prints its table: Markdown for the README, aligned columns for a terminal."""
from __future__ import annotations


def render(head, rows, markdown: bool) -> list[str]:
    """The table's lines: ``head`` and ``rows`` are sequences of strings."""
    if markdown:
        return (["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
                + ["| " + " | ".join(r) + " |" for r in rows])
    widths = [max(len(x) for x in col) for col in zip(head, *rows)]
    return ["  ".join(x.ljust(w) for x, w in zip(r, widths)) for r in (head, *rows)]

"""The installed Qt binding keeps Python's reference counts straight.

PySide6 6.12.0 takes one reference off ``None`` on every binding call that returns nothing
(``QLabel.setText``, every ``QPainter`` call). On Python < 3.12, where ``None`` is not immortal, the
count reaches zero after some 10^4 calls and the viewer aborts with "Fatal Python error: none_dealloc";
pyproject.toml excludes that release. These tests fail on a binding with that defect: the count of
references to ``None`` must not fall over many calls (a few references held by caches may come and go).
"""

from __future__ import annotations

import sys

from PySide6.QtGui import QColor, QImage, QPainter
from PySide6.QtWidgets import QLabel

CALLS = 2000


def test_calls_returning_nothing_leave_none_alone(qtbot) -> None:
    label = QLabel()
    qtbot.addWidget(label)
    before = sys.getrefcount(None)
    for i in range(CALLS):
        label.setText(str(i))
    after = sys.getrefcount(None)
    assert after > before - CALLS // 20, f"None refcount {before} -> {after} over {CALLS} setText calls"


def test_painter_calls_leave_none_alone() -> None:
    image = QImage(64, 64, QImage.Format.Format_RGB32)
    painter = QPainter(image)
    try:
        before = sys.getrefcount(None)
        for i in range(CALLS):
            painter.setPen(QColor(i % 256, 0, 0))
            painter.drawPoint(i % 64, i // 64 % 64)
        after = sys.getrefcount(None)
    finally:
        painter.end()
    assert after > before - CALLS // 20, f"None refcount {before} -> {after} over {2 * CALLS} painter calls"

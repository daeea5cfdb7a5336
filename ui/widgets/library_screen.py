"""Library browser (thesis §5.3.3, Figs. 5.3, 5.9–5.11): hierarchy tree, thumbnails, index filter sliders,
type check boxes, and the ColorSnap view — matches, the library cloud in Lab space (3D, drag to turn)
and the design beside its match on the two halves of a cylinder.

Every paint the filter passes gets a thumbnail: they are fitted (one batch per step) and rendered in a
background task, with the viewer's progress indicator (:class:`~ui.widgets.tasks.TaskProgress`), and
the list fills step by step; a paint that cannot be rendered is listed with the reason. A new filter
stops the running task. Double-clicking a thumbnail makes that paint the current design (undoable).
ColorSnap runs in the background too, with its own indicator."""

from __future__ import annotations

import math

import numpy as np
from PySide6.QtCore import QPointF, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QIcon, QMouseEvent, QPainter, QPen
from PySide6.QtWidgets import (
    QCheckBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QSlider,
    QTreeWidget,
    QTreeWidgetItem,
    QVBoxLayout,
    QWidget,
)

from station.formulate.library import PAINT_TYPES
from station.formulate.snap import view_data
from station.model import FaceFlopTravelGloss
from station.model.errors import FitError
from ui.models.document import DesignDocument
from ui.models.library import LibraryModel, Thumbnail, bar_images
from ui.models.view import ViewModel, ViewSettings
from ui.widgets.common import lab_colours, pixmap_from_array
from ui.widgets.render_view import make_render_view
from ui.widgets.tasks import TaskProgress, TaskThread

SLIDER_STEPS = 100
INDICES = ("flop", "chroma", "hue_shift")
#: Labelled values on the Lab cloud's axes: L* 0–100 (vertical), a* and b* −80…80 (CIE units).
L_TICKS = (0.0, 25.0, 50.0, 75.0, 100.0)
AB_TICKS = (-80.0, -40.0, 40.0, 80.0)
#: Caption of the Lab cloud (wrapped to the widget's width).
CLOUD_CAPTION = "Lab space: library at 45°, design 15→45→110° (yellow), matches (rings)"


class LabCloud(QWidget):
    """Library paints at 45° as points in Lab space (orthographic, drag to turn), the design's three
    angles joined by a line, and the matches ringed."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.data: dict | None = None
        self.yaw, self.pitch = 30.0, 20.0
        self._drag: QPointF | None = None
        self.setMinimumSize(240, 200)

    def set_data(self, data: dict | None) -> None:
        """View data from :func:`station.formulate.snap.view_data`."""
        self.data = data
        if data is not None:
            self._cloud = np.asarray(data["cloud"]["lab"], float)
            self._cloud_rgb = lab_colours(self._cloud)
        self.update()

    def project(self, lab: np.ndarray) -> np.ndarray:
        """Lab (..., 3) → widget pixels (..., 2): a* right, L* up, b* into the screen, then turned."""
        lab = np.asarray(lab, float)
        x, y, z = lab[..., 1], lab[..., 0] - 50.0, -lab[..., 2]
        cy, sy = math.cos(math.radians(self.yaw)), math.sin(math.radians(self.yaw))
        cp, sp = math.cos(math.radians(self.pitch)), math.sin(math.radians(self.pitch))
        x, z = cy * x + sy * z, -sy * x + cy * z
        y = cp * y - sp * z
        s = min(self.width(), self.height()) / 220.0
        return np.stack([self.width() / 2 + s * x, self.height() / 2 - s * y], -1)

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        # the background and the cloud's 2×2 px points as one image: one painter call, not one per
        # point (each call from Python costs the same as a whole image, and the cloud has 1500)
        w, h = max(self.width(), 1), max(self.height(), 1)
        canvas = np.empty((h, w, 3), np.uint8)
        canvas[:] = (40, 40, 44)
        if self.data is not None:
            pts = np.trunc(self.project(self._cloud)).astype(int)
            for dx in (0, 1):
                for dy in (0, 1):
                    x, y = pts[:, 0] + dx, pts[:, 1] + dy
                    inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
                    canvas[y[inside], x[inside]] = self._cloud_rgb[inside]
        p.drawPixmap(0, 0, pixmap_from_array(canvas))
        p.setPen(QPen(QColor(120, 120, 120), 1))
        for a, b in (((50, -80, 0), (50, 80, 0)), ((50, 0, -80), (50, 0, 80)), ((0, 0, 0), (100, 0, 0))):
            pa, pb = self.project(np.array(a)), self.project(np.array(b))
            p.drawLine(QPointF(*pa), QPointF(*pb))
        for lab, _text in self._ticks():
            c = self.project(np.asarray(lab))
            p.drawLine(QPointF(c[0] - 2, c[1]), QPointF(c[0] + 2, c[1]))
            p.drawLine(QPointF(c[0], c[1] - 2), QPointF(c[0], c[1] + 2))
        for text, rect, axis_name in self.axis_labels():
            p.setPen(QColor(235, 235, 235) if axis_name else QColor(160, 160, 160))
            p.drawText(rect, Qt.AlignmentFlag.AlignCenter, text)
        if self.data is not None:
            p.setPen(QPen(QColor(255, 255, 255), 1))
            for m in self.data["matches"]:
                x, y = self.project(np.asarray(m["lab"][1]))
                p.drawEllipse(QPointF(x, y), 5, 5)
            d = self.project(np.asarray(self.data["design"]))
            p.setPen(QPen(QColor(255, 220, 0), 2))
            for i in range(len(d) - 1):
                p.drawLine(QPointF(*d[i]), QPointF(*d[i + 1]))
            p.drawEllipse(QPointF(*d[0]), 4, 4)
        p.setPen(QColor(200, 200, 200))
        p.drawText(self.caption_rect(), Qt.TextFlag.TextWordWrap, CLOUD_CAPTION)
        p.end()

    def caption_rect(self) -> QRectF:
        """Where the caption is drawn: the widget's top, as many lines as its width needs."""
        r = self.fontMetrics().boundingRect(
            0, 0, max(self.width() - 12, 1), 10_000, Qt.TextFlag.TextWordWrap, CLOUD_CAPTION
        )
        return QRectF(6, 2, self.width() - 12, r.height())

    @staticmethod
    def _ticks() -> list[tuple[tuple[float, float, float], str]]:
        """(Lab point, label) of every tick: L* on the vertical axis, a* and b* through L* = 50."""
        out = [((v, 0.0, 0.0), f"{v:.0f}") for v in L_TICKS]
        out += [((50.0, v, 0.0), f"{v:+.0f}") for v in AB_TICKS]
        out += [((50.0, 0.0, v), f"{v:+.0f}") for v in AB_TICKS]
        return out

    def axis_labels(self) -> list[tuple[str, QRectF, bool]]:
        """(text, rectangle, is an axis name) of the axis names (L*, a*, b* at the positive ends) and the
        tick labels, each placed beside its point and kept inside the widget."""
        fm = self.fontMetrics()
        items: list[tuple[str, tuple[float, float, float], bool]] = [
            ("L*", (100.0 + 8.0, 0.0, 0.0), True),
            ("a*", (50.0, 80.0 + 12.0, 0.0), True),
            ("b*", (50.0, 0.0, 80.0 + 12.0), True),
        ]
        items += [(text, lab, False) for lab, text in self._ticks()]
        out = []
        for text, lab, is_name in items:
            x, y = self.project(np.asarray(lab))
            w, h = fm.horizontalAdvance(text) + 4, fm.height()
            left = min(max(x + 3.0, 0.0), self.width() - w)
            top = min(max(y - h / 2, 0.0), self.height() - h)
            out.append((text, QRectF(left, top, w, h), is_name))
        return out

    def mousePressEvent(self, event: QMouseEvent) -> None:
        self._drag = event.position()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is not None:
            d = event.position() - self._drag
            self._drag = event.position()
            self.yaw += d.x() * 0.5
            self.pitch = max(-89.0, min(89.0, self.pitch + d.y() * 0.5))
            self.update()

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        self._drag = None


class LibraryScreen(QWidget):
    """Browser on the left, ColorSnap on the right."""

    def __init__(self, model: LibraryModel, document: DesignDocument, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.document = document
        lib = model.library
        self.title = QLabel(
            f"{lib.name}: {len(lib)} paints" + (" — SYNTHETIC demo data" if lib.synthetic else "")
        )
        self.title.setWordWrap(True)  # a long library name must not widen the screen
        self._build_tree()
        types, form = self._build_filters()
        self._build_thumbs()
        browse = QVBoxLayout()
        browse.addWidget(self.title)
        browse.addWidget(self.tree, 1)
        browse.addLayout(types)
        browse.addLayout(form)
        browse.addWidget(self.count)
        browse.addWidget(self.thumb_busy)
        browse.addWidget(self.thumbs, 2)
        snap_box = self._build_snap_box()

        lay = QHBoxLayout(self)
        lay.addLayout(browse, 2)
        lay.addWidget(snap_box, 3)
        model.events.filtered.connect(self._on_filtered)
        model.events.snapped.connect(self._on_snapped)
        self._on_filter()

    # ---------------------------------------------------------------- builders
    def _build_tree(self) -> None:
        """The hierarchy of the library (set, kind, group) with the number of paints in each."""
        lib, model = self.model.library, self.model
        self.tree = QTreeWidget()
        self.tree.setHeaderLabels(["hierarchy", "paints"])
        root = QTreeWidgetItem(["all", str(len(lib))])
        self.tree.addTopLevelItem(root)
        for set_name, kinds in model.counts().items():
            s_item = QTreeWidgetItem([set_name, str(sum(sum(g.values()) for g in kinds.values()))])
            root.addChild(s_item)
            for kind, groups in kinds.items():
                k_item = QTreeWidgetItem([kind, str(sum(groups.values()))])
                s_item.addChild(k_item)
                for g, n in groups.items():
                    k_item.addChild(QTreeWidgetItem([g, str(n)]))
        self.tree.expandToDepth(1)
        # the names in full ("metallics", "chromatic"), never elided: the first column fits its contents
        self.tree.header().setSectionResizeMode(0, QHeaderView.ResizeMode.ResizeToContents)
        self.tree.header().setStretchLastSection(True)
        self.tree.itemClicked.connect(self._on_tree)

    def _build_filters(self) -> tuple[QHBoxLayout, QFormLayout]:
        """The paint-type check boxes and a low/high slider pair per index; (their row, their form)."""
        model = self.model
        self.type_boxes = {t: QCheckBox(t) for t in PAINT_TYPES}
        types = QHBoxLayout()
        for b in self.type_boxes.values():
            b.setChecked(True)
            b.toggled.connect(self._on_filter)
            types.addWidget(b)
        self.sliders: dict[str, tuple[QSlider, QSlider, tuple[float, float], QLabel]] = {}
        form = QFormLayout()
        for name in INDICES:
            lo_s, hi_s = QSlider(Qt.Orientation.Horizontal), QSlider(Qt.Orientation.Horizontal)
            for s, v in ((lo_s, 0), (hi_s, SLIDER_STEPS)):
                s.setRange(0, SLIDER_STEPS)
                s.setValue(v)
                s.valueChanged.connect(self._on_filter)
            label = QLabel()
            self.sliders[name] = (lo_s, hi_s, model.index_range(name), label)
            row = QHBoxLayout()
            row.addWidget(lo_s)
            row.addWidget(hi_s)
            row.addWidget(label)
            form.addRow(f"{name.replace('_', ' ')} index", row)
        return types, form

    def _build_thumbs(self) -> None:
        """The count of shown paints and their thumbnails (rendered in the background)."""
        self.count = QLabel()
        self.thumbs = QListWidget()
        self.thumbs.setIconSize(QSize(40, 40))
        self.thumbs.setUniformItemSizes(True)
        self.thumbs.setToolTip("double-click a paint to make it the current design")
        self.thumbs.itemDoubleClicked.connect(self._on_thumb)
        self.thumb_busy = TaskProgress()
        self.thumb_task: TaskThread | None = None
        self._pending: list[Thumbnail] = []  # made by the running task, not yet listed
        self._unrendered = 0
        self._restart = False
        self._closing = False
        self._thumbs_running = False  # from start until its finished signal reached this thread
        self._snap_running = False
        self._rows = np.zeros(0, dtype=int)
        self._item_rows: list[int] = []  # library row of each list item, in list order

    def _build_snap_box(self) -> QGroupBox:
        """ColorSnap: the button, its matches, the Lab cloud and the design | match comparison."""
        document = self.document
        self.snap_btn = QPushButton("ColorSnap current design")
        self._snap_design = document.design
        self.snap_btn.clicked.connect(lambda: self.snap())
        self.snap_busy = TaskProgress()
        self.snap_task: TaskThread | None = None
        self.matches = QListWidget()
        self.matches.setIconSize(QSize(64, 14))
        self.matches.currentRowChanged.connect(self._on_match)
        self.use_btn = QPushButton("Use selected match as design")
        self.use_btn.clicked.connect(self.use_match)
        self.warnings = QLabel()
        self.warnings.setWordWrap(True)
        self.cloud = LabCloud()
        self.compare_model = ViewModel(ViewSettings(shape="cylinder"))
        self.compare = make_render_view(self.compare_model)
        self.compare.setMinimumSize(200, 180)
        snap_box = QGroupBox("ColorSnap")
        sl = QVBoxLayout(snap_box)
        sl.addWidget(self.snap_btn)
        sl.addWidget(self.snap_busy)
        sl.addWidget(self.matches)
        sl.addWidget(self.use_btn)
        sl.addWidget(self.warnings)
        views = QHBoxLayout()
        views.addWidget(self.cloud, 1)
        col = QVBoxLayout()
        col.addWidget(QLabel("design (left) | match (right)"))
        col.addWidget(self.compare, 1)
        views.addLayout(col, 1)
        sl.addLayout(views, 2)
        return snap_box

    # ---------------------------------------------------------------- filter
    def _slider_bounds(self, name: str) -> tuple[float | None, float | None]:
        lo_s, hi_s, (vmin, vmax), label = self.sliders[name]
        lo = vmin + (vmax - vmin) * lo_s.value() / SLIDER_STEPS
        hi = vmin + (vmax - vmin) * hi_s.value() / SLIDER_STEPS
        label.setText(f"{lo:.2f} – {hi:.2f}")
        return (None if lo_s.value() == 0 else lo, None if hi_s.value() == SLIDER_STEPS else hi)

    def _on_filter(self, *_args) -> None:
        kw: dict[str, object] = {"types": frozenset(t for t, b in self.type_boxes.items() if b.isChecked())}
        for name in INDICES:
            lo, hi = self._slider_bounds(name)
            if lo is not None and hi is not None and lo > hi:
                lo, hi = hi, lo
            kw[name] = (lo, hi)
        self.model.set_filter(**kw)

    def _on_tree(self, item: QTreeWidgetItem, _col: int) -> None:
        path: list[str] = []
        node: QTreeWidgetItem | None = item
        while node is not None and node.parent() is not None:
            path.insert(0, node.text(0))
            node = node.parent()
        keys = ("set_name", "kind", "group")
        self.model.set_filter(**{k: (path[i] if i < len(path) else None) for i, k in enumerate(keys)})

    def _on_filtered(self) -> None:
        """Show the filtered paints' thumbnails: a task still making those of the previous filter is
        stopped first (after its current step), then the new one starts."""
        self.thumbs.clear()
        self._item_rows = []
        self._unrendered = 0
        self._rows = self.model.rows
        self._count_text()
        if self.thumb_task is not None and self._thumbs_running:  # its queued results still to come
            self.thumb_task.cancel()
            self._restart = True  # _on_thumbs_finished starts the new filter's thumbnails
            return
        self._start_thumbs()

    def _start_thumbs(self) -> None:
        self._restart = False
        rows = self._rows
        if rows.size == 0 or self._closing:
            self.thumb_task = None
            return
        pending: list[Thumbnail] = []
        self._pending = pending
        task = TaskThread(lambda progress: self.model.thumbnails(rows, pending.extend, progress), pure=True)
        # the indicator first: its end-of-task slot runs before ours, which may start the next task
        self.thumb_busy.watch(task, f"thumbnails of {rows.size} paints…", steps=int(rows.size))
        task.progress.connect(self._on_thumb_progress)
        task.succeeded.connect(self._on_thumbs_done)
        task.failed.connect(self._on_thumbs_failed)
        task.cancelled.connect(self._on_thumbs_cancelled)
        task.finished.connect(self._on_thumbs_finished)
        self.thumb_task = task
        self._thumbs_running = True
        task.start()

    def _on_thumbs_finished(self) -> None:
        self._thumbs_running = False
        if self._restart:
            self._start_thumbs()

    def _count_text(self, note: str = "") -> None:
        n, shown = int(self._rows.size), self.thumbs.count()
        text = f"{n} paints match"
        if shown < n:
            text += f" ({shown} thumbnails so far)"
        if self._unrendered:
            text += f"; {self._unrendered} cannot be rendered (reason in the list)"
        self.count.setText(text + note)

    def _add_pending(self) -> None:
        items, pending = self._pending[:], self._pending
        del pending[: len(items)]
        lib = self.model.library
        self.thumbs.setUpdatesEnabled(False)
        for t in items:  # items made with the list as parent: no further call per item
            label = f"{lib.codes[t.row]}  {lib.types[t.row]}  {lib.gloss_gu[t.row]:.0f} GU"
            self._item_rows.append(int(t.row))
            if t.image is not None:
                QListWidgetItem(QIcon(pixmap_from_array(t.image)), label, self.thumbs)
            else:
                it = QListWidgetItem(f"{label}  — cannot render: {t.error}", self.thumbs)
                it.setToolTip(str(t.error))
                it.setFlags(it.flags() & ~Qt.ItemFlag.ItemIsEnabled)
                self._unrendered += 1
        self.thumbs.setUpdatesEnabled(True)

    def row_of(self, item: QListWidgetItem) -> int:
        """Library row of a thumbnail list item."""
        return self._item_rows[self.thumbs.row(item)]

    def _on_thumb_progress(self, _done: int, _text: str) -> None:
        if not self._restart:  # else the step belongs to a filter no longer shown
            self._add_pending()
            self._count_text()

    def _on_thumbs_done(self, _n: object) -> None:
        self._on_thumb_progress(0, "")

    def _on_thumbs_cancelled(self) -> None:
        if not self._restart:  # Cancel pressed: keep what was made
            self._add_pending()
            self._count_text(" — thumbnails stopped")

    def _on_thumbs_failed(self, message: str) -> None:
        if not self._restart:
            self._add_pending()
            self._count_text(f" — thumbnails failed: {message}")

    @property
    def idle(self) -> bool:
        """No thumbnail or ColorSnap task is running or has results still to show."""
        return not (self._restart or self._thumbs_running or self._snap_running)

    def _on_thumb(self, item: QListWidgetItem) -> None:
        """Double-click: the paint becomes the current design (undoable, named after the paint)."""
        self.pick(self.row_of(item))

    def pick(self, row: int) -> None:
        """Make library paint *row* the current design (a paint without a fit says why, in the list's
        tooltip and the warnings line)."""
        code = self.model.library.codes[row]
        try:
            design = self.model.design_of(row)
        except FitError as exc:
            self.warnings.setText(f"{code} cannot be used: {exc}")
            return
        self.document.set_design(design, f"library {code}")

    # ---------------------------------------------------------------- ColorSnap
    def snap(self, design: FaceFlopTravelGloss | None = None) -> None:
        """ColorSnap *design* (default: the current design) in the background; the matches appear when
        it is done (a second request while one runs is ignored)."""
        if self._snap_running:
            return
        target = design if design is not None else self.document.design
        self._snap_design = target
        task = TaskThread(lambda _progress: self.model.compute_snap(target), pure=True)
        task.succeeded.connect(self._on_snap_done)
        task.failed.connect(self._on_snap_failed)
        task.finished.connect(self._on_snap_finished)
        self.snap_task = task
        self._snap_running = True
        self.snap_btn.setEnabled(False)
        self.warnings.setText("")
        self.snap_busy.watch(task, f"ColorSnap in {len(self.model.library)} paints…")
        task.start()

    def _on_snap_done(self, result) -> None:
        self.model.accept_snap(result)

    def _on_snap_failed(self, message: str) -> None:
        self.warnings.setText(f"ColorSnap failed: {message}")

    def _on_snap_finished(self) -> None:
        self._snap_running = False
        self.snap_btn.setEnabled(True)

    def _on_snapped(self, result) -> None:
        self.matches.clear()
        rows = np.array([m.index for m in result.matches])
        bars: np.ndarray | list[np.ndarray] = bar_images(self.model.library, rows) if rows.size else []
        for m, img in zip(result.matches, bars, strict=True):
            de = " / ".join(f"{v:.1f}" for v in m.de_per_angle)
            self.matches.addItem(
                QListWidgetItem(
                    QIcon(pixmap_from_array(img)), f"{m.code}  ΣΔE {m.sum_de:.2f} ({de} at 15/45/110°)"
                )
            )
        self.warnings.setText("\n".join(result.warnings))
        self.cloud.set_data(view_data(self.model.library, result, max_cloud=1500))
        if result.matches:
            self.matches.setCurrentRow(0)

    def _on_match(self, row: int) -> None:
        res = self.model.snap_result
        if res is None or not 0 <= row < len(res.matches):
            return
        try:
            match = self.model.design_of(res.matches[row].index)
        except FitError as exc:
            self.warnings.setText(f"{res.matches[row].code} cannot be shown: {exc}")
            return
        self.compare_model.show(self._snap_design, match)

    def use_match(self) -> None:
        """Make the selected match's design current (undoable)."""
        res = self.model.snap_result
        row = self.matches.currentRow()
        if res is not None and 0 <= row < len(res.matches):
            m = res.matches[row]
            try:
                design = self.model.design_of(m.index)
            except FitError as exc:
                self.warnings.setText(f"{m.code} cannot be used: {exc}")
                return
            self.document.set_design(design, f"ColorSnap {m.code}")

    def closeEvent(self, event) -> None:
        self._closing = True
        self._restart = False
        for task in (self.thumb_task, self.snap_task):
            if task is not None:
                task.cancel()
                task.wait()
        self.model.events.filtered.disconnect(self._on_filtered)
        self.model.events.snapped.disconnect(self._on_snapped)
        self.compare.close()
        super().closeEvent(event)

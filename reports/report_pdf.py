"""The report as a PDF: A4 pages laid out with matplotlib's PDF backend (no browser, no new dependency).

A small flow layout: blocks of :mod:`.report_content` go down the page from a cursor; text wraps
at the page width, tables wrap their widest columns and repeat their heading row after a page
break, figures take the full text width. Each page carries the lab and report number at the
top, "page n of m" at the bottom, and "not for release" on every page when the report says so.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

from flowcurve.reports.report_content import Facts, Figure, Heading, Link, Para, Report, Table

PAGE_W, PAGE_H = 8.27, 11.69  # A4, inches
MARGIN_X, MARGIN_TOP, MARGIN_BOTTOM = 0.6, 0.75, 0.7
TEXT_W = PAGE_W - 2 * MARGIN_X
CHAR_W = 0.62  # average glyph width (with margin) of DejaVu Sans, in units of the font size
PT = 1.0 / 72.0  # inch per point
SIZES = {"title": 15.0, 2: 11.5, 3: 9.5, "body": 8.0, "table": 6.8, "small": 6.5}
COLOURS = {"warn": "#a00000", "note": "#555555", "": "#222222"}


def _chars(width_in: float, size: float) -> int:
    """How many average characters of font ``size`` fit in ``width_in``."""
    return max(4, int(width_in / (size * CHAR_W * PT)))


def _line_h(size: float) -> float:
    return size * 1.3 * PT


def _column_widths(columns: list[str] | None, rows: list[list[str]], size: float) -> list[int]:
    """Each column's width in characters: its longest cell, the widest narrowed first to fit the text width,
    but not below their longest word (no word broken while others have room)."""
    ncol = len(columns) if columns else max(len(r) for r in rows)
    budget = _chars(TEXT_W, size) - 2 * ncol
    natural = [max([len(str(c)) for c in ([columns[i]] if columns else [])] + [len(str(r[i])) for r in rows if i < len(r)] + [3])
               for i in range(ncol)]
    cells = [[columns[i]] if columns else [] for i in range(ncol)]
    for r in rows:
        for i in range(min(ncol, len(r))):
            cells[i].append(str(r[i]))
    floor = [min(16, max([len(w) for c in col for w in c.split()] + [3])) for col in cells]
    widths = list(natural)
    while sum(widths) > budget:
        shrinkable = [k for k in range(ncol) if widths[k] > floor[k]]
        if not shrinkable:
            break
        i = max(shrinkable, key=lambda k: widths[k])
        widths[i] = max(floor[i], int(widths[i] * 0.85))
    return widths


class _Layout:
    def __init__(self, report: Report):
        import matplotlib.pyplot as plt

        self._plt = plt
        self.report = report
        self.pages = []
        self.y = 0.0
        self._new_page()

    # -- pages ------------------------------------------------------------------------------
    def _new_page(self) -> None:
        fig = self._plt.figure(figsize=(PAGE_W, PAGE_H))
        self.pages.append(fig)
        self.fig = fig
        lab = self.report.lab
        fig.text(MARGIN_X / PAGE_W, 1 - 0.4 / PAGE_H, f"{lab.name} — {self.report.title}", fontsize=SIZES["small"], color="#555")
        fig.text(1 - MARGIN_X / PAGE_W, 1 - 0.4 / PAGE_H, f"report {self.report.number}, revision {lab.revision}, issued "
                 f"{self.report.issued}", fontsize=SIZES["small"], color="#555", ha="right")
        if self.report.not_for_release:
            fig.text(0.5, 1 - 0.22 / PAGE_H, self.report.not_for_release.upper(), fontsize=SIZES[3], color="#a00000",
                     weight="bold", ha="center")
        fig.add_artist(self._plt.Line2D([MARGIN_X / PAGE_W, 1 - MARGIN_X / PAGE_W], [1 - 0.5 / PAGE_H] * 2, color="#999", lw=0.5))
        self.y = MARGIN_TOP

    def _room(self, height: float) -> None:
        if self.y + height > PAGE_H - MARGIN_BOTTOM:
            self._new_page()

    def _text(self, x_in: float, text: str, size: float, **kw) -> None:
        self.fig.text(x_in / PAGE_W, 1 - self.y / PAGE_H, text, fontsize=size, va="top", ha="left", **kw)

    # -- blocks -----------------------------------------------------------------------------
    def title(self) -> None:
        """Draw the report's title."""
        self._room(_line_h(SIZES["title"]) * 2)
        self._text(MARGIN_X, self.report.title, SIZES["title"], weight="bold")
        self.y += _line_h(SIZES["title"]) * 1.4

    def figure_height(self, b: Figure) -> float:
        """The height figure ``b`` takes at the text width, inches."""
        import matplotlib.image as mpimg

        h_px, w_px = mpimg.imread(b.path).shape[:2]
        return min(TEXT_W * h_px / w_px, PAGE_H - MARGIN_TOP - MARGIN_BOTTOM - 3 * _line_h(SIZES["small"]))

    def heading(self, b: Heading, keep: float = 0.0) -> None:
        """A heading, kept on one page with ``keep`` inches of what follows (at least four lines)."""
        size = SIZES.get(b.level, SIZES[3])
        self._room(_line_h(size) * 1.6 + max(keep, _line_h(SIZES["body"]) * 4))
        self.y += _line_h(size) * 0.5
        self._text(MARGIN_X, b.text, size, weight="bold")
        self.y += _line_h(size) * 1.1

    def para(self, text: str, kind: str = "", url: str | None = None) -> None:
        """Draw a wrapped paragraph (a note smaller; a link when ``url``)."""
        size = SIZES["body"] if kind != "note" else SIZES["small"] + 0.5
        for line in textwrap.wrap(text, _chars(TEXT_W, size)) or [""]:
            self._room(_line_h(size))
            self._text(MARGIN_X, line, size, color=COLOURS.get(kind, "#222"), url=url)
            self.y += _line_h(size)
        self.y += _line_h(size) * 0.4

    def table(self, columns: list[str] | None, rows: list[list[str]], caption: str = "", *, size: float = SIZES["table"]) -> None:
        """Draw a table with wrapped cells, its header repeated on each page."""
        widths = _column_widths(columns, rows, size)
        scale = TEXT_W / sum(w + 2 for w in widths)
        col_w = [(w + 2) * scale for w in widths]
        line = _line_h(size)

        def wrap(row):
            """Each cell of ``row`` wrapped to its column's width."""
            return [textwrap.wrap(str(c), w) or [""] for c, w in zip(row, widths)]

        def draw(row, bold=False, shade=False):
            """Draw one table row."""
            cells = wrap(row)
            height = max(len(c) for c in cells) * line + 0.5 * line
            x = MARGIN_X
            if shade:
                self.fig.add_artist(self._plt.Rectangle((MARGIN_X / PAGE_W, 1 - (self.y + height) / PAGE_H), TEXT_W / PAGE_W,
                                                        height / PAGE_H, color="#ececec", lw=0, zorder=0))
            for lines, w in zip(cells, col_w):
                self.fig.text((x + 0.04) / PAGE_W, 1 - (self.y + 0.2 * line) / PAGE_H, "\n".join(lines), fontsize=size,
                              va="top", ha="left", linespacing=1.15, weight="bold" if bold else "normal")
                x += w
            self.y += height
            self.fig.add_artist(self._plt.Line2D([MARGIN_X / PAGE_W, (MARGIN_X + TEXT_W) / PAGE_W], [1 - self.y / PAGE_H] * 2,
                                                 color="#bbbbbb", lw=0.4))
            return height

        def row_height(row):
            """The height of one table row."""
            return max(len(c) for c in wrap(row)) * line + 0.5 * line

        header_h = row_height(columns) if columns else 0.0
        caption_size = SIZES["small"] + 0.5
        caption_h = (len(textwrap.wrap(caption, _chars(TEXT_W, caption_size))) + 0.4) * _line_h(caption_size) if caption else 0.0
        self._room(caption_h + header_h + (row_height(rows[0]) if rows else 0))  # the caption stays with its table
        if caption:
            self.para(caption, "note")
        if columns:
            draw(columns, bold=True, shade=True)
        for row in rows:
            h = row_height(row)
            if self.y + h > PAGE_H - MARGIN_BOTTOM:
                self._new_page()
                if columns:
                    draw(columns, bold=True, shade=True)
            draw(row)
        self.y += line * 0.6

    def figure(self, b: Figure) -> None:
        """Draw figure ``b`` at the text width."""
        import matplotlib.image as mpimg

        img = mpimg.imread(b.path)
        h_px, w_px = img.shape[:2]
        width = TEXT_W
        height = width * h_px / w_px
        limit = PAGE_H - MARGIN_TOP - MARGIN_BOTTOM - 3 * _line_h(SIZES["small"])
        if height > limit:
            width, height = width * limit / height, limit
        self._room(height + 2 * _line_h(SIZES["small"]))
        ax = self.fig.add_axes([MARGIN_X / PAGE_W, 1 - (self.y + height) / PAGE_H, width / PAGE_W, height / PAGE_H])
        ax.imshow(img, interpolation="antialiased")
        ax.set_axis_off()
        self.y += height + 0.05
        self.para(b.caption, "note")

    def number_pages(self) -> None:
        """Write "page i of n" on every page."""
        total = len(self.pages)
        for i, fig in enumerate(self.pages, 1):
            fig.text(1 - MARGIN_X / PAGE_W, 0.35 / PAGE_H, f"page {i} of {total}", fontsize=SIZES["small"], ha="right", color="#555")
            fig.text(MARGIN_X / PAGE_W, 0.35 / PAGE_H, f"report {self.report.number}", fontsize=SIZES["small"], color="#555")


def write_pdf(report: Report, path) -> Path:
    """Lay the report out on A4 pages and write it to ``path``."""
    from matplotlib.backends.backend_pdf import PdfPages

    layout = lay_out(report)
    try:
        with PdfPages(path, metadata={"Title": report.title, "Creator": "flowcurve report"}) as pdf:
            for fig in layout.pages:
                pdf.savefig(fig)
        return Path(path)
    finally:
        for fig in layout.pages:
            layout._plt.close(fig)


def page_texts(report: Report) -> list[list[str]]:
    """The texts drawn on each PDF page, in drawing order (what :func:`write_pdf` saves)."""
    layout = lay_out(report)
    try:
        return [[t.get_text() for t in fig.texts] for fig in layout.pages]
    finally:
        for fig in layout.pages:
            layout._plt.close(fig)


def lay_out(report: Report) -> _Layout:
    """The report on numbered A4 pages (matplotlib figures; the caller closes them)."""
    layout = _Layout(report)
    try:
        layout.title()
        for i, b in enumerate(report.blocks):
            if isinstance(b, Heading):
                following = report.blocks[i + 1] if i + 1 < len(report.blocks) else None
                layout.heading(b, layout.figure_height(following) if isinstance(following, Figure) else 0.0)
            elif isinstance(b, Para):
                layout.para(b.text, b.kind)
            elif isinstance(b, Facts):
                layout.table(None, [[k, v] for k, v in b.rows], size=SIZES["body"])
            elif isinstance(b, Table):
                layout.table(b.columns, b.rows, b.caption)
            elif isinstance(b, Figure):
                layout.figure(b)
            elif isinstance(b, Link):
                layout.para(b.text, url=b.href)
        layout.number_pages()
        return layout
    except BaseException:
        for fig in layout.pages:
            layout._plt.close(fig)
        raise

"""Read a report's index.html as a browser would see its references."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path

# Attributes through which a page or an inline SVG can load or link another
# resource (xlink:href included: SVG's <use> and <image>).
REFERENCING = {"src", "href", "xlink:href", "srcset", "data", "poster", "action", "background"}
NAMESPACES = {"http://www.w3.org/2000/svg", "http://www.w3.org/1999/xlink"}


@dataclass
class Page(HTMLParser):
    """The tags, references, ids, figures and the table of trials pointed out."""

    references: list[tuple[str, str, str]] = field(default_factory=list)
    ids: list[str] = field(default_factory=list)
    tags: set[str] = field(default_factory=set)
    figures: list[str] = field(default_factory=list)
    svg_in_figure: dict[str, int] = field(default_factory=dict)
    urls: list[str] = field(default_factory=list)
    pointed_out: dict[int, str] = field(default_factory=dict)
    _figure: str | None = None
    _table: str = ""
    _row: list[str] = field(default_factory=list)
    _cell: list[str] | None = None
    _section: str = ""

    def __post_init__(self) -> None:
        super().__init__(convert_charrefs=True)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.add(tag)
        for name, value in attrs:
            value = value or ""
            if name in REFERENCING:
                self.references.append((tag, name, value))
            if name == "id":
                self.ids.append(value)
            if name.startswith("xmlns") and value not in NAMESPACES:
                self.references.append((tag, name, value))
            self.urls.extend(re.findall(r"url\(\s*['\"]?([^'\")]*)", value))
        ident = dict(attrs).get("id") or ""
        if tag == "h2":
            self._section = ident
        if tag == "figure":
            self._figure = ident
            self.figures.append(ident)
        if tag == "svg" and self._figure is not None:
            self.svg_in_figure[self._figure] = self.svg_in_figure.get(self._figure, 0) + 1
        if tag == "tr":
            self._row = []
        if tag == "td":
            self._cell = []

    def handle_endtag(self, tag: str) -> None:
        if tag == "figure":
            self._figure = None
        if tag == "td" and self._cell is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        if tag == "tr" and self._section == "trials" and self._row:
            self.pointed_out[int(self._row[0])] = self._row[2]

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)
        self.urls.extend(re.findall(r"url\(\s*['\"]?([^'\")]*)", data))


def parse_page(path: Path) -> Page:
    """The report page at ``path``, parsed."""
    page = Page()
    page.feed(path.read_text(encoding="utf-8"))
    page.close()
    return page


def assert_self_contained(page: Page) -> None:
    """The page refers to no other file: every reference is a data: URI or an
    anchor in the page itself, and no style, script or font comes from elsewhere."""
    ids = set(page.ids)
    assert len(ids) == len(page.ids), "ids repeat: the inline plots would clash"
    for tag, name, value in page.references:
        assert value.startswith(("data:", "#")), (tag, name, value)
        if value.startswith("#"):
            assert value[1:] in ids, f"{tag} {name}={value} points at nothing in the page"
    for url in page.urls:
        assert url.startswith(("data:", "#")), url
        if url.startswith("#"):
            assert url[1:] in ids, url
    assert not page.tags & {"script", "link", "iframe", "img", "object", "embed"}, page.tags
    for figure in page.figures:
        assert page.svg_in_figure.get(figure) == 1, figure

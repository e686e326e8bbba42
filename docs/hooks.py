"""MkDocs hooks: the "Measured figures" page is rendered from the benches' JSON at build time
(``docs/figures.py``), so the site never shows a stale or hand-copied figure."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path
from typing import Any

_spec = importlib.util.spec_from_file_location("figures", Path(__file__).with_name("figures.py"))
assert _spec is not None and _spec.loader is not None
figures = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(figures)


_INCLUDE = re.compile(r"^<!-- include (bench/[\w/.-]+\.md) -->$", re.MULTILINE)


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    if page.file.src_uri == "figures.md":
        return figures.figures_page()
    # a bench's own table where a page names it, so prose pages quote no figure by hand
    here = Path(__file__).parent
    return _INCLUDE.sub(lambda m: (here / m.group(1)).read_text(), markdown)

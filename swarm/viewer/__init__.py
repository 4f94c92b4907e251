"""The browser replay viewer: one self-contained HTML page per recording (``swarm view run.swr``).

``template.html``, ``viewer.css`` and ``viewer.js`` are package data; :func:`build_html` inlines them and
the recording into a page that needs no server and no network (see :mod:`swarm.viewer.build`). May import:
``swarm.record`` and what it may.
"""

from .build import build_html, title_of, write_html

__all__ = ["build_html", "title_of", "write_html"]

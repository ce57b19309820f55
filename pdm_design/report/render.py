"""Render a matplotlib Figure to bytes (for write_atomic), reproducibly."""

from __future__ import annotations

import io


def render_figure(figure, fmt: str, *, dpi: int = 120) -> bytes:
    """PNG or SVG bytes of `figure`, the same bytes for the same figure (no dates, fixed salt)."""
    from matplotlib import rc_context
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(figure)
    buffer = io.BytesIO()
    metadata = {"Date": None} if fmt == "svg" else {"Software": None}
    with rc_context({"svg.hashsalt": "pdm-design"}):
        figure.savefig(buffer, format=fmt, dpi=dpi, metadata=metadata)
    return buffer.getvalue()

"""matplotlib figures for the pages: drawn off-screen (Agg), written whole, images shown through
one display transform."""

from __future__ import annotations

from pathlib import Path


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path: Path, **savefig) -> Path:
    """Write ``fig`` to ``path`` through a partial file moved into place, and close it."""
    plt = pyplot()
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    if path.suffix == ".png":
        savefig = {"pil_kwargs": {"optimize": True}, **savefig}
    fig.savefig(partial, **savefig)
    plt.close(fig)
    partial.replace(path)
    return path


def display(linear):
    """Scene-linear radiance as an sRGB-encoded picture: clipped to 1, the exact sRGB curve."""
    import numpy as np

    from addon.reference.tonemap import linear_to_srgb

    return linear_to_srgb(np.clip(np.asarray(linear, np.float64)[..., :3], 0.0, 1.0))


def image_panel(ax, picture, title: str = "", fontsize: float | None = 8, ylabel: str = "",
                interpolation: str | None = None) -> None:
    """``picture`` (display-encoded) in ``ax``, without ticks, titled; ``interpolation``
    matplotlib's (None: its default, which filters a picture shown smaller than it is)."""
    ax.imshow(picture, interpolation=interpolation)
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=fontsize)
    if ylabel:
        ax.set_ylabel(ylabel, fontsize=fontsize)

"""What a reader sees in a figure written to a PNG file."""
import numpy as np
from matplotlib.image import imread


def assert_drawn(path, min_side=300, min_coloured=5e-4):
    """The figure at ``path`` is at least ``min_side`` pixels each way and shows its data: more than
    ``min_coloured`` of its pixels are coloured (matplotlib draws axes, ticks and text in greys, so
    a figure with empty axes has none; every data line and patch here is coloured)."""
    rgb = imread(path)[..., :3]
    coloured = np.any(np.abs(rgb - rgb.mean(axis=-1, keepdims=True)) > 0.1, axis=-1)
    assert min(rgb.shape[:2]) >= min_side and coloured.mean() > min_coloured, (path, rgb.shape, coloured.mean())

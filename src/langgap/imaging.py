"""Image preprocessing that public VLA checkpoints were trained with."""

from __future__ import annotations

import numpy as np
from PIL import Image


def resize_with_pad(image: np.ndarray, height: int, width: int) -> np.ndarray:
    """Fit a uint8 (H, W, 3) image into (height, width) keeping its aspect ratio, centred on black.

    The semantics of `tf.image.resize_with_pad` with PIL bilinear resampling, which is what openpi's
    LIBERO client sends (`openpi_client.image_tools.resize_with_pad`); a test pins the two equal.
    An image already of the target size is returned unchanged.
    """
    rows, cols = image.shape[:2]
    if (rows, cols) == (height, width):
        return image
    scale = max(cols / width, rows / height)
    new_rows, new_cols = int(rows / scale), int(cols / scale)
    resized = Image.fromarray(image).resize((new_cols, new_rows), resample=Image.BILINEAR)
    canvas = np.zeros((height, width, *image.shape[2:]), dtype=image.dtype)
    top, left = max(0, (height - new_rows) // 2), max(0, (width - new_cols) // 2)
    canvas[top : top + new_rows, left : left + new_cols] = np.asarray(resized)
    return canvas

"""Episode GIFs: frames quantised as they arrive, written as one looping GIF."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


class GifRecorder:
    """Collects every ``stride``-th (H, W, 3) uint8 frame, quantised to a 64-colour palette as it arrives (a
    500-step episode of raw 640 x 640 frames would hold 600 MB), and writes them as one looping GIF."""

    def __init__(self, stride: int = 1, scale: float = 1.0) -> None:
        self.stride = max(int(stride), 1)
        self.scale = float(scale)
        self.images: list[Any] = []
        self._count = 0

    def append(self, frame: np.ndarray) -> None:
        from PIL import Image

        if self._count % self.stride == 0:
            image = Image.fromarray(np.asarray(frame, dtype=np.uint8))
            if self.scale != 1.0:
                size = (max(1, round(image.width * self.scale)), max(1, round(image.height * self.scale)))
                image = image.resize(size, Image.Resampling.LANCZOS)
            self.images.append(image.quantize(colors=64))
        self._count += 1

    def save(self, path: str | Path, fps: float) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        first, *rest = self.images
        duration = int(round(1000.0 * self.stride / fps))
        first.save(path, save_all=True, append_images=rest, duration=duration, loop=0)
        return path

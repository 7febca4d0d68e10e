"""Prints the 64-point Poisson-disk set of `methods/pcss.wgsl` as WGSL.

Mitchell's best-candidate sampling in the unit disk: each new point is, of
32 k uniform candidates, the one farthest from the k points so far, so every
prefix of the sequence is itself well spread (pcss takes the first n x n).
The first point is the candidate nearest the centre. Seeded: reproducible.

    python3 scripts/poisson_disk.py
"""

from __future__ import annotations

import numpy as np


def best_candidate(count: int = 64, seed: int = 2005) -> np.ndarray:
    rng = np.random.default_rng(seed)
    points: list[np.ndarray] = []
    for k in range(count):
        m = 32 * (k + 1)
        radius, angle = np.sqrt(rng.random(m)), 2 * np.pi * rng.random(m)
        candidates = np.stack([radius * np.cos(angle), radius * np.sin(angle)], 1)
        if points:
            nearest = np.min(np.linalg.norm(candidates[:, None] - np.array(points)[None], axis=2), axis=1)
            points.append(candidates[np.argmax(nearest)])
        else:
            points.append(candidates[np.argmin(np.linalg.norm(candidates, axis=1))])
    return np.array(points)


def main() -> None:
    points = best_candidate()
    for i in range(0, len(points), 4):
        print("    " + ", ".join(f"vec2<f32>({x:.5f}, {y:.5f})" for x, y in points[i : i + 4]) + ",")


if __name__ == "__main__":
    main()

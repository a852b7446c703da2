"""Cameras of the preview: look-at, perspective and orthographic projections (column-vector
(4, 4) matrices), the named view directions and the framing of a set of world points."""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "FOV_DEG",
    "look_at",
    "perspective",
    "ortho",
    "camera_direction",
    "frame",
    "key_and_fill",
]

FOV_DEG = 40.0


def look_at(eye: np.ndarray, target: np.ndarray, up: np.ndarray) -> np.ndarray:
    f = target - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    v = np.eye(4)
    v[0, :3], v[1, :3], v[2, :3] = r, u, -f
    v[:3, 3] = -v[:3, :3] @ eye
    return v


def perspective(fovy: float, aspect: float, near: float, far: float) -> np.ndarray:
    f = 1.0 / math.tan(fovy / 2)
    p = np.zeros((4, 4))
    p[0, 0], p[1, 1] = f / aspect, f
    p[2, 2], p[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
    p[3, 2] = -1.0
    return p


def ortho(half_x: float, half_y: float, near: float, far: float) -> np.ndarray:
    """(4, 4) orthographic projection of the box |x| <= half_x, |y| <= half_y, near..far."""
    p = np.eye(4)
    p[0, 0], p[1, 1] = 1.0 / half_x, 1.0 / half_y
    p[2, 2], p[2, 3] = -2.0 / (far - near), -(far + near) / (far - near)
    return p


def camera_direction(camera: str, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Unit vector from the target towards the eye (front = +Z side)."""
    size = hi - lo
    if camera == "front":
        az, el = 0.0, 6.0
    elif camera == "three-quarter":
        az, el = 35.0, 20.0
    else:  # auto: look down more on wide, flat scenes (a temple plan), less on tall ones
        az, el = 35.0, (12.0 if size[1] > max(size[0], size[2]) else 28.0)
    az, el = math.radians(az), math.radians(el)
    return np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])


def frame(corners: np.ndarray, direction: np.ndarray, aspect: float):
    """Eye, target and distance such that every corner fits the 40° view with a margin."""
    target = 0.5 * (corners.min(axis=0) + corners.max(axis=0))
    f = -direction
    r = np.cross(f, [0.0, 1.0, 0.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    tan_v = math.tan(math.radians(FOV_DEG) / 2) / 1.1
    tan_h = tan_v * aspect
    d = 0.0
    for _ in range(2):  # second pass re-centres the projected box
        rel = corners - target
        x, y, z = rel @ r, rel @ u, rel @ f
        d = max(float(np.max(np.abs(x) / tan_h - z)), float(np.max(np.abs(y) / tan_v - z)))
        depth = d + z
        sx, sy = x / depth, y / depth
        target = target + r * 0.5 * (sx.max() + sx.min()) * d + u * 0.5 * (sy.max() + sy.min()) * d
    radius = 0.5 * float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0)))
    d = max(d, 1e-6 + radius * 0.05)
    return target + direction * d, target, d, radius


def key_and_fill(direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit key light (high on the camera's right) and fill light (low from its left) for a
    camera looking from ``direction`` (3,); the key depends on the view's azimuth only."""
    az = math.atan2(direction[0], direction[2])
    key = np.array([math.sin(az + 1.1) * 0.75, 0.66, math.cos(az + 1.1) * 0.75])
    fill = np.array([math.sin(az - 1.4) * 0.8, 0.25, math.cos(az - 1.4) * 0.8])
    return key / np.linalg.norm(key), fill / np.linalg.norm(fill)

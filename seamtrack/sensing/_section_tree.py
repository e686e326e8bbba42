"""The bounding-volume hierarchy of the plane-section fan (:mod:`seamtrack.sensing.section`):
built once per mesh, in numba."""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL

#: Triangles per leaf of the hierarchy.
LEAF_SIZE = 4


class SectionIndex(NamedTuple):
    """A bounding-volume hierarchy over a mesh's triangles (arrays, built by :func:`build`).

    Attributes
    ----------
    lo, hi : (m, 3) float
        Each node's box.
    child : (m,) int64
        An inner node's first child (the second follows it); a leaf's first entry in ``order``.
    leaf_count : (m,) int64
        A leaf's number of triangles; 0 for an inner node.
    order : (f,) int64
        Triangle indices, leaf by leaf.
    """

    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    child: NDArray[np.int64]
    leaf_count: NDArray[np.int64]
    order: NDArray[np.int64]

    @property
    def nbytes(self) -> int:
        """Memory held by the index."""
        return sum(a.nbytes for a in self)


def build(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> SectionIndex:
    """The hierarchy of a mesh: each node's triangles split in halves at the median of their
    boxes' centres along the longest axis (quickselect), down to :data:`LEAF_SIZE`; each node's
    box the union of its children's. O(n log n).

    Memory: 56 bytes a triangle (the boxes in float64 and the order), plus 24 bytes a triangle
    (the centres) while it is built.
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.ascontiguousarray(faces, dtype=np.int64)
    lo, hi, child, count, order = _build(v, f, LEAF_SIZE, _nodes(len(f)))
    return SectionIndex(lo=lo, hi=hi, child=child, leaf_count=count, order=order)


def _nodes(n: int) -> int:
    """How many nodes :func:`_build` makes for n triangles (halving until a leaf)."""
    memo: dict[int, int] = {}

    def count(m: int) -> int:
        if m <= LEAF_SIZE:
            return 1
        if m not in memo:
            memo[m] = 1 + count(m // 2) + count(m - m // 2)
        return memo[m]

    return count(n)


@numba.njit(**KERNEL)
def _select(
    order: NDArray[np.int64], centre: NDArray[np.float64], axis: int, start: int, end: int,
    kth: int,
) -> None:  # fmt: skip
    """Reorder ``order[start:end]`` so that the entry at ``kth`` has the centre it would have
    sorted along ``axis``, none greater before it and none smaller after (quickselect)."""
    left, right = start, end - 1
    while right > left:
        mid = (left + right) // 2
        a, b, c = centre[order[left], axis], centre[order[mid], axis], centre[order[right], axis]
        pivot = max(min(a, b), min(max(a, b), c))  # the median of the three
        i, j = left, right
        while i <= j:
            while centre[order[i], axis] < pivot:
                i += 1
            while centre[order[j], axis] > pivot:
                j -= 1
            if i <= j:
                order[i], order[j] = order[j], order[i]
                i += 1
                j -= 1
        if kth <= j:
            right = j
        elif kth >= i:
            left = i
        else:
            return


@numba.njit(**KERNEL)
def _build(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], leaf: int, nodes: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.int64],
           NDArray[np.int64]]:  # fmt: skip
    f = faces.shape[0]
    order = np.arange(f)
    centre = _box_centres(vertices, faces)
    lo = np.empty((nodes, 3))
    hi = np.empty((nodes, 3))
    child = np.zeros(nodes, dtype=np.int64)
    count = np.zeros(nodes, dtype=np.int64)
    # The topology: each range of ``order`` split at its median along the longest axis of its
    # centres' box, depth first; children allocated in pairs, so a child's index is always
    # larger than its parent's.
    stack_node = np.empty(256, dtype=np.int64)
    stack_start = np.empty(256, dtype=np.int64)
    stack_end = np.empty(256, dtype=np.int64)
    stack_node[0], stack_start[0], stack_end[0] = 0, 0, f
    top = 1
    used = 1
    while top > 0:
        top -= 1
        node, start, end = stack_node[top], stack_start[top], stack_end[top]
        if end - start <= leaf:
            child[node] = start
            count[node] = end - start
            continue
        mid = (start + end) // 2
        _select(order, centre, _longest_axis(centre, order, start, end), start, end, mid)
        child[node] = used
        stack_node[top], stack_start[top], stack_end[top] = used, start, mid
        stack_node[top + 1], stack_start[top + 1], stack_end[top + 1] = used + 1, mid, end
        top += 2
        used += 2
    _node_boxes(vertices, faces, order, child, count, used, lo, hi)
    return lo, hi, child, count, order


@numba.njit(**KERNEL)
def _box_centres(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """Each face's bounding box's centre."""
    f = faces.shape[0]
    centre = np.empty((f, 3))
    for k in range(f):
        for a in range(3):
            p, q, r = vertices[faces[k, 0], a], vertices[faces[k, 1], a], vertices[faces[k, 2], a]
            centre[k, a] = 0.5 * (min(p, q, r) + max(p, q, r))
    return centre


@numba.njit(**KERNEL)
def _longest_axis(
    centre: NDArray[np.float64], order: NDArray[np.int64], start: int, end: int
) -> int:
    """The axis along which the centres ``order[start:end]`` spread the most (the first of
    equals)."""
    cmin = np.full(3, np.inf)
    cmax = np.full(3, -np.inf)
    for j in range(start, end):
        for a in range(3):
            cmin[a] = min(cmin[a], centre[order[j], a])
            cmax[a] = max(cmax[a], centre[order[j], a])
    axis = 0
    for a in range(1, 3):
        if cmax[a] - cmin[a] > cmax[axis] - cmin[axis]:
            axis = a
    return axis


@numba.njit(**KERNEL)
def _node_boxes(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    order: NDArray[np.int64],
    child: NDArray[np.int64],
    count: NDArray[np.int64],
    used: int,
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
) -> None:
    """Fill the nodes' boxes, children before parents: a leaf's from its faces' vertices, an
    inner node's from its two children."""
    for node in range(used - 1, -1, -1):
        if count[node] > 0:
            for a in range(3):
                lo[node, a] = np.inf
                hi[node, a] = -np.inf
            for j in range(child[node], child[node] + count[node]):
                k = order[j]
                for a in range(3):
                    for c in range(3):
                        lo[node, a] = min(lo[node, a], vertices[faces[k, c], a])
                        hi[node, a] = max(hi[node, a], vertices[faces[k, c], a])
        else:
            first = child[node]
            for a in range(3):
                lo[node, a] = min(lo[first, a], lo[first + 1, a])
                hi[node, a] = max(hi[first, a], hi[first + 1, a])

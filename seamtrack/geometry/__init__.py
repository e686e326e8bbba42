"""Geometry: SE(3) helpers (``T_a_b`` poses) and the seam path (``Seam``). Imports nothing else of
seamtrack."""

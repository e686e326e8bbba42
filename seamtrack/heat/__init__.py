"""Heat: the temperature field of the moving arc in closed form (Rosenthal's point, line and
image sources), the materials' thermal constants, and the welding distortion it drives.

Needs numpy and scipy only; nothing here is imported until a scene or a user asks for it.
"""

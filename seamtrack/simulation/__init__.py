"""Simulation: the scene schema and its validation, assembling what a scene asks for, the loop and
its scoring."""

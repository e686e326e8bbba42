"""Features: line fits, the joint-family and generic extractors, and synthetic profiles with
truth."""

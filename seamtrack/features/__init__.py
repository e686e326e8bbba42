"""Features: one line geometry, the segmentation front end, the extractors (one subpackage per
family: vgroove, plates, groove, generic), and synthetic profiles with truth."""

"""The generic extractor: the sharpest turn of a profile's slope, for joints no family model
describes."""

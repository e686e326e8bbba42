"""The groove extractor: the 7 points of an empty or partly filled groove (V, narrow gap, U) for
multi-pass welding, with its fits and kernels."""

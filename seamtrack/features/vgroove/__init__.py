"""The v-groove extractor (a V's two bevels, their root faces and the root between them) and the V
search that the fillet and outside-corner extractors share."""

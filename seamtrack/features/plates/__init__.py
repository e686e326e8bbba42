"""The two-plate extractors (square butt and lap): the plates' lines, the gap or step between them,
and the compiled two-line pieces the corner extractors share."""

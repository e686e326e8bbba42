"""Many runs at once: parameter sweeps on a process pool or a Dask cluster."""

"""Benchmarks and the speed/accuracy trade (``seamtrack bench``); the library never imports them."""

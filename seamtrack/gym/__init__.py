"""The Gymnasium environment (``import seamtrack.gym``). Needs the ``gym`` extra:
``pip install seamtrack[gym]``."""

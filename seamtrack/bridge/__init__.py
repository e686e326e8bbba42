"""Other processes: ROS 2 messages without ROS, MCAP recordings, the lockstep bridge
(``seamtrack serve``). Needs the ``ros`` extra: ``pip install seamtrack[ros]``."""

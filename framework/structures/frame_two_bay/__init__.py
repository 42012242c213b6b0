"""A three-storey two-bay OpenSees frame (ours), the diagnosis study's user-like model."""

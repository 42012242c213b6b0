"""Structure 1: the laboratory frame (3-DOF analytical and detailed OpenSees models, SPEC 5)."""

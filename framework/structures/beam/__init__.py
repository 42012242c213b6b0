"""Structure 3: the simply supported beam for damage estimation (SPEC 7)."""

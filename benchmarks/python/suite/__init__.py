"""The benchmark suite behind docs/results.md: the paper's comparison and the physical validations."""

"""The benchmark suite behind docs/results.md: accuracy, cost, sampling and user gains."""

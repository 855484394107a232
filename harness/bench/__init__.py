"""Benchmarks that print tables and plots, never pass/fail: render times (timing.py), BVH
throughput (throughput.py), error against run time (convergence.py); their records (records.py)."""

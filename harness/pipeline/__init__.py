"""The case pipeline: one case rendered and judged (case.py), the matrix of cases with its
pages and files (matrix.py), where the cases run (executor.py), the progress line (progress.py)."""

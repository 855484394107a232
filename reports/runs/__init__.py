"""The harness runs: each a function over cases (check, report, stress, sweeps, bench)."""

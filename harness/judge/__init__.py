"""Metrics, thresholds and verdicts: how a candidate's images are judged against a reference."""

"""Why a case fails: its findings (case.py), the cause search (causes.py,
jitter_causes.py) and the course program's quirks (quirks.py)."""

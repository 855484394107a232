"""What is kept on disk: finished cases and cached renders (results.py), the reference's
distributions (distribution.py, shipped.py), the per-machine cache (disk_cache.py), output
folders swapped in whole (staging.py)."""

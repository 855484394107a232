"""A submission given as sources: unpacked (sources.py), built with CMake in the sandbox
(cmake.py)."""

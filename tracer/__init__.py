"""raycheck's own Dr.Jit ray tracer reproducing the course renderer."""

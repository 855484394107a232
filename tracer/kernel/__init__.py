"""Dr.Jit plumbing: loading Dr.Jit against a suitable libLLVM (backend), array types and the
course's vector formulas (vecmath), run-time scene values (uniforms), frozen launches (frozen)
and the per-lane traversal stack (lane_stack)."""

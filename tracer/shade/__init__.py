"""What a ray sees: the course camera (camera), Phong shading and the mirror recursion
(shading), the background and cube maps (background), and the parts of a color image
(auxiliary)."""

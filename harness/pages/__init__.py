"""HTML pages, SVG plots and the pictures they show."""

"""Maps, the first stage: the registry of dataset YAMLs, maps made on first use from pinned
sources, image reading, and the grid of cells a map is cut into."""

"""Per-part triangle meshes in the normalised object frame."""

"""Exporters of a structure plus part meshes to URDF, MJCF, glTF and Blender."""

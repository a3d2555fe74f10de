"""Importers of articulated objects from URDF (PartNet-Mobility layout) and MJCF.

Entry point: ``data_pipeline.importers.source.import_object(path)``. It accepts a URDF or MJCF
file, or an object directory (PartNet-Mobility: ``mobility.urdf`` + ``semantics.txt`` +
``textured_objs/``; otherwise the one URDF or MJCF file in it) and returns an ``ImportedObject``:
the structure O (canonical), part meshes and boxes in the normalised frame, and meta (scale in
metres per nu, source, part names, warnings). ``output.write_imported`` writes it to a folder.

Modules: ``frames`` (transforms), ``meshes`` (geometry loading),
``urdf`` / ``mjcf`` (readers into a ``kinematic_tree.KinematicTree``; ``safe_xml.parse_xml`` parses
untrusted XML through defusedxml; ``ros_package`` resolves ``package://`` mesh URIs), ``kinematic_tree``
(which links are parts, which joint moves each), ``material_guess``, ``assemble``.
This package imports nothing heavy on its own, so the CLI can register quickly.
"""

"""Reading and writing files: images (`lumos.io.image_files`) and meshes (`lumos.io.meshes`).

The submodules are not imported here so that `import lumos` stays fast: Pillow, OpenEXR and trimesh are
loaded only when a file is actually read or written.
"""

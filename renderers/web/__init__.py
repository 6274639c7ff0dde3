"""The project's JavaScript workspace (``package.json``: the glTF validator, three.js,
drei's vanilla build, esbuild) and the Python side of what runs in it."""

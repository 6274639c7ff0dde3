"""drei's ``Caustics`` (``@pmndrs/vanilla``, the algorithm of ``@react-three/drei``'s
``<Caustics>``) as the harness method ``drei-caustics``: the scene exported to glTF,
rendered by three.js in headless Chromium, its caustic texture carried onto the
receiver's (u, v) map (``docs/drei-caustics.md``).

Modules: :mod:`.params` (the component's options from a scene, and the scenes it
refuses), :mod:`.mapping` (texture to receiver map, flux conserved), :mod:`.bundle`
(the page's script, bundled by esbuild), :mod:`.driver` (Chromium through Playwright),
:mod:`.method` (the method). Playwright is imported only when a page is opened.
"""

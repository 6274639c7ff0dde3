"""The scene every test compares on: the bundled glass sphere, made small so the
whole run takes about a minute on two CPU cores (about 50 s to render its reference
once; later runs read it from the reference cache)."""

#: The bundled scene, by name.
SCENE = "glass_sphere"
#: Renderer settings overriding the scene's: 100k photons on 2 seeds, a 48 x 48
#: receiver map and small caustics-mapping textures.
SMALL = {"photons": 100_000, "seeds": 2, "spp": 2, "grid": 48, "caustic_map": 128,
         "positions_map": 128, "shadow_map": 128, "receiver_map": [48, 48]}
#: Camera image size (pixels).
RESOLUTION = (48, 48)

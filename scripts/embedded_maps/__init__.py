"""The recipes of the embedded maps in ``data/maps/``: ``scripts/make_maps.py`` runs the
three made from registry sources, ``scripts/make_geonrw_map.py`` the one made from a GeoNRW tile.

Modules, from the shared pieces up:

``seeding``
    The one seed and the random stream of every stage of every map.
``texture``, ``quilting``
    Smooth noise, tone and colour helpers, random crops, and image quilting.
``sources``
    The Sentinel-2 scene (from a pinned PyPI sdist) and the scikit-image photos.
``label_cleanup``, ``legend``
    Label-map clean-up shared by two maps; legend classes and their YAML text.
``sentinel_coast``, ``aerial_mosaic`` (with ``aerial_trail``), ``reef_mosaic``
    One builder per map.
``geonrw_essen``
    The GeoNRW tile: pinned source files, crop and class mapping (``scripts/make_geonrw_map.py``).
``build``, ``map_files``
    Building a map by name and checking it; writing its three files and comparing them
    with the committed ones.
"""

"""Procedural floor plans, one concept a module (the recipe: :mod:`map2map.maps.floorplan`).

``layout`` (outline, rooms), ``doors`` (adjacency graph, spanning tree, doors and
openings), ``raster`` (notches, walls), ``furniture``, ``check`` (reachability for a
disc robot), ``generate`` (:func:`generate_floorplan` as steps), ``documents``
(layout JSON) and ``figures``. Import the public names from
:mod:`map2map.maps.floorplan`.
"""

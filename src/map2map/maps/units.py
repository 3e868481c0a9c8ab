"""DXF drawing units: the names the ``units`` option accepts and their size in metres.

Kept apart from :mod:`map2map.maps.dxf` (which imports shapely and ezdxf) so that the
command line can offer the names cheaply, and apart from :mod:`map2map.maps.formats`
(which dispatches to :mod:`~map2map.maps.dxf`) so that neither imports the other.

Examples
--------
>>> sorted(UNITS)
['cm', 'ft', 'in', 'm', 'mm']
>>> UNITS["mm"]
0.001
"""

#: DXF drawing unit names accepted by ``units`` and their size in metres.
UNITS = {"mm": 0.001, "cm": 0.01, "m": 1.0, "in": 0.0254, "ft": 0.3048}

__all__ = ["UNITS"]

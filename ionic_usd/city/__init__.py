"""City plans (GeoJSON or grid), lots → buildings, porticoes → columns: numpy and shapely."""

from ionic_usd.city.layout import Footprint, TempleFit, fit_temple, porticus_columns
from ionic_usd.city.plan import CityPlan, Lot, Porticus, grid_plan, read_geojson

__all__ = [
    "CityPlan",
    "Footprint",
    "Lot",
    "Porticus",
    "TempleFit",
    "fit_temple",
    "grid_plan",
    "porticus_columns",
    "read_geojson",
]

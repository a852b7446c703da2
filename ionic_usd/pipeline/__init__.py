"""The coordinator: prototype specs, the content-addressed prototype cache, the Dask build,
and the city build that ties them together."""

from ionic_usd.pipeline.build import PrototypeCache, build_prototypes
from ionic_usd.pipeline.city import CityOptions, build_city
from ionic_usd.pipeline.spec import TempleSpec, temple_spec

__all__ = ["CityOptions", "PrototypeCache", "TempleSpec", "build_city", "build_prototypes",
           "temple_spec"]

"""What to write: the product's vocabulary and descriptions, with no ``pxr``.

(Named ``blueprint``, not ``spec``: tools take a folder named ``spec/`` for tests.)

Generation, the pipeline and :mod:`ionic_usd.usd` share these; ``usd/`` keeps the writers
(and the one reader) and turns a description into layers. Nothing under ``blueprint/`` imports
``pxr`` (``tests/test_layering.py`` imports it in a fresh interpreter and checks), so a mesh
worker or the up-to-date check that needs a name or an option loads no USD.

- :mod:`ionic_usd.blueprint.layers`: the file and prim names of the folders the package writes
  (standard library only);
- :mod:`ionic_usd.blueprint.materials`: a material's texture paths, the stone maps' tile size;
- :mod:`ionic_usd.blueprint.asset`: a component asset's description (meshes, instancers, variant
  sets, materials), which :func:`ionic_usd.usd.asset.write_asset` authors;
- :mod:`ionic_usd.blueprint.column_asset`: the column asset's variant vocabulary, its build options
  and its description (:func:`~ionic_usd.blueprint.column_asset.column_asset_spec`);
- :mod:`ionic_usd.blueprint.temple`: the column a temple's layout calls for and the column
  asset it instances;
- :mod:`ionic_usd.blueprint.hypotheses`: the hypotheses' variant vocabulary on ``/Temple``, the
  part and column-group prim names, and the checks of what the composer can realise;
- :mod:`ionic_usd.blueprint.city`: a city's temples and street columns as instance arrays, which
  :func:`ionic_usd.usd.city.compose_city` authors;
- :mod:`ionic_usd.blueprint.temple_plan`: the temple's plan (:func:`plan_temple`, validated
  before anything is written) and the ``detail`` vocabulary and kernel values, which
  :func:`ionic_usd.usd.temple.write_temple` authors.

The levels of detail are :mod:`ionic_usd.lod`.
"""

"""Built-in structures, one package each (model, data, effects, geometry, reproduction, simulated tests),
and the registry that names them."""

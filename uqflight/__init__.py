"""uqflight: uncertainty quantification campaigns on a JSBSim flight-dynamics model."""
__version__ = "0.1.0"

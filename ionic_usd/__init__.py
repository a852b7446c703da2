"""ionic_usd: procedural Ionic-order columns and temples authored as OpenUSD scenes."""

__version__ = "0.1.0"

//! Built-in mesh generators: rectangle, disc, polygon with holes.

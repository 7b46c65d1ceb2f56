"""panorama: spherical images (equirectangular, cubemaps, perspective views) built on ``ibr``."""

"""Colour-space facts of Blender's scene linear space, shared by the material compiler
(materials/convert.py: the Wavelength node) and the numpy twins (reference/thin_film.py)."""

#: CIE XYZ -> scene linear (Rec. 709), as Cycles' xyz_to_rgb holds it (the Wavelength node): Blender
#: 5.0's, the inverse of the matrix whose Y row is materials/convert.py's LUMA (Rec. 709's primaries
#: and D65's xy); Blender 4.x's, the inverse of the one whose Y row is LUMA_4.
XYZ_TO_RGB = ((3.2409699, -1.5373832, -0.4986108), (-0.9692436, 1.8759675, 0.0415551),
              (0.0556301, -0.2039770, 1.0569715))
XYZ_TO_RGB_4 = ((3.2404548, -1.5371389, -0.4985316), (-0.9692664, 1.8760109, 0.0415561),
                (0.0556434, -0.2040259, 1.0572252))

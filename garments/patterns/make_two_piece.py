"""Writes two_piece.dxf with ezdxf (PyPI): two pattern pieces in the AAMA / ASTM D6673 layer
convention (millimetres), used by garments/patterns/two_piece.ron and tests/pattern_import.rs.

"left" and "right" are 200 x 300 mm rectangles; their side seams are marked by three notches
each (both ends and the middle), so each side splits into two notch spans. Each piece is a
block inserted in the ENTITIES section, with its boundary on layer 1, notches as short LINEs
on layer 4 (first point on the cut line), the grain line on layer 7 and an internal line on
layer 8; its name and size are TEXT on layer 1.

    python make_two_piece.py   # rewrites two_piece.dxf
"""
import sys
import ezdxf


def piece(doc, name, outline, notches, grain, internal):
    blk = doc.blocks.new(name=name.upper())
    blk.add_lwpolyline(outline, close=True, dxfattribs={"layer": "1"})
    for (x, y, dx, dy) in notches:
        blk.add_line((x, y), (x + dx, y + dy), dxfattribs={"layer": "4"})
    blk.add_line(grain[0], grain[1], dxfattribs={"layer": "7"})
    blk.add_line(internal[0], internal[1], dxfattribs={"layer": "8"})
    blk.add_text(f"Piece Name: {name}", dxfattribs={"layer": "1", "insert": (20, 200), "height": 5})
    blk.add_text("Size: M", dxfattribs={"layer": "1", "insert": (20, 190), "height": 5})
    return blk


def main(path):
    doc = ezdxf.new("R2000")
    doc.header["$INSUNITS"] = 4  # millimetres
    for layer in ["1", "4", "7", "8"]:
        doc.layers.add(layer)
    rect = [(0, 0), (200, 0), (200, 300), (0, 300)]
    # Notches point into the piece (5 mm cuts) from the seam side.
    piece(doc, "left", rect, [(200, 0, -5, 0), (200, 150, -5, 0), (200, 300, -5, 0)], ((100, 50), (100, 250)), ((50, 100), (50, 200)))
    piece(doc, "right", rect, [(0, 0, 5, 0), (0, 150, 5, 0), (0, 300, 5, 0)], ((100, 50), (100, 250)), ((150, 100), (150, 200)))
    msp = doc.modelspace()
    msp.add_blockref("LEFT", (0, 0))
    msp.add_blockref("RIGHT", (250, 0))
    msp.add_text("Style Name: two_piece", dxfattribs={"insert": (0, -20), "height": 5})
    msp.add_text("Sample Size: M", dxfattribs={"insert": (0, -30), "height": 5})
    doc.saveas(path)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "two_piece.dxf")

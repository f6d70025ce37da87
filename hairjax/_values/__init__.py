"""The plain values every layer reads (docs/architecture.md, "Layers"): strands and their
tangents, the camera and the light. Validated at construction, immutable, NumPy only; this
package imports no other package of hairjax."""

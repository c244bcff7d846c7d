#pragma once

// The built-in ground-truth shape of the workspace synthesizer, and the
// normalisation every ground truth goes through.
//
// The built-in shape is a sphere-like body (radius ~32 units before
// normalisation) carrying fine relief (egg-crate bumps and grooves of
// amplitude ~1 unit and wavelength ~6-9 units), cut by a plane: the flat cap
// meets the curved body in a sharp circular crease (dihedral angle ~72
// degrees) that is an exact polyline of mesh edges (the relief fades out
// towards the crease, so the crease ring lies exactly in the cut plane). The
// flat cap is tilted towards -y so that a ring of cameras sees it from
// several sides. The mesh is closed, 2-manifold, genus 0 and consistently
// oriented (counter-clockwise = outward).

#include "colmap_io/ply.h"

namespace mr {

struct BuiltinShapeOptions {
  // Target edge length in scene units (the shape is built at roughly its
  // final size, bounding-box diagonal ~100). 0.45 gives ~150k faces. Range (0, 10].
  double edge_length = 0.45;
  // Amplitude of the relief in scene units. Range [0, 5].
  double relief_amplitude = 1.0;
  // Polar angle (degrees) of the cut: the flat cap is the part of the sphere
  // with polar angle < cut_angle_deg. The crease's dihedral angle is about
  // this value. Range [20, 90].
  double cut_angle_deg = 72;
  // Tilt of the cut plane's normal from the world +z axis (degrees), towards -y.
  // Range [0, 90].
  double tilt_deg = 35;

  bool Check() const;
};

// Builds the built-in shape (not yet normalised; see NormalizeMesh).
TriangleMesh MakeBuiltinShape(const BuiltinShapeOptions& options);

// Translates and scales V in place so that its bounding box is centred at the
// origin and has diagonal `diagonal`. Throws InputError if V is empty or
// degenerate (zero diagonal). Returns the scale factor applied.
double NormalizeMesh(double diagonal, Eigen::MatrixXd* V);

// Largest dihedral angle (degrees, 0 = flat) between the normals of two faces
// sharing an edge; 0 for a mesh with no interior edge.
double MaxDihedralAngleDeg(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

}  // namespace mr

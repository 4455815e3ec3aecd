// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_H
#define NORMAL_ORIENTATION_H

/// \file Normal_orientation.h
/// Umbrella header: everything of the in-core package.

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Flip_criteria.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/parameters.h>
#include <Normal_orientation/solvers/Exhaustive_solver.h>
#include <Normal_orientation/solvers/Lsa_tr_solver.h>
#include <Normal_orientation/solvers/Mst_solver.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>

#endif // NORMAL_ORIENTATION_H

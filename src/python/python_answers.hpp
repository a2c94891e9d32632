// What a Python controller answers, read as rilbed's: a step's (left, right) or
// rilbed.Output, and step_all's (n, 2) wheels with their behaviours. Every answer is
// checked like any input from outside rilbed (fuzz_python_answers feeds them arbitrary
// Python values). Call with the GIL held.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "agents/controller_group.hpp"

namespace rilbed::python {

/// A step's answer: a sequence of two real numbers (rounded, clamped to ±127; behaviour
/// "python"), or a rilbed.Output (its behaviour interned). Throws agents::ControllerError
/// naming `who` for anything else, a NaN or an infinity; a Python error raised while
/// reading it (a sequence whose items raise) propagates as pybind11::error_already_set.
agents::ControlOutput output_from_python(pybind11::handle result, const std::string& who);

/// step_all's answer for the robots `robot_ids` (the rows' order): an array-like of shape
/// (n, 2), or a tuple (that, behaviour) with behaviour one str or n of them. Throws
/// agents::ControllerError naming `who` for another shape, a non-finite wheel, behaviours
/// that are not strings or not n of them; Python errors propagate as for
/// output_from_python().
std::vector<agents::GroupAnswer> swarm_answers(pybind11::handle result, std::span<const int> robot_ids,
                                               const std::string& who);

}  // namespace rilbed::python

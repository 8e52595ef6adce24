#pragma once
/// \file
/// Convenience header for the Lie group types.
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

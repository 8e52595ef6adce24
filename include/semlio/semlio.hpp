#pragma once
/// \file
/// Umbrella header: everything semlio offers.

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/logger.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

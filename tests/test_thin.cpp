#include <drape/drape.hpp>
#include <catch2/catch.hpp>

#pragma once
// Counts operator new calls in this test binary (alloc_counter.cpp replaces the global operators).
namespace phaco::test {

// False under AddressSanitizer, whose own operator new must stay in place.
bool allocation_counting_available();
// Number of allocations made, by any thread, while counting was on.
long allocations_counted();
void start_counting_allocations();  // resets the count
void stop_counting_allocations();

}  // namespace phaco::test

#pragma once
// Counts operator new calls made on chosen threads only (alloc_counter.cpp replaces the global
// operators for this test binary): the haptic thread marks itself after start-up, and every
// allocation it makes from then on is counted, while other threads allocate freely.
namespace phaco::test {

// False under AddressSanitizer or ThreadSanitizer, whose own operator new must stay in place.
bool haptic_allocation_counting_available();
// Marks (or unmarks) the calling thread: its allocations count while the window is open.
void count_allocations_on_this_thread(bool on);
// Opens the window with the count reset to zero / closes it.
void open_allocation_window();
void close_allocation_window();
long allocations_on_marked_threads();

}  // namespace phaco::test

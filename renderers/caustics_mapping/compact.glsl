// Stream compaction in one work group of 1024 invocations, the same on every run:
// the indices i < n for which compact_listed(i) holds go, in increasing order, to
// compact_store(slot, i), and compact_total gets their number. Each invocation takes
// a run of consecutive indices and counts its own; an inclusive scan of the counts
// over the group (Hillis and Steele) gives each run its first slot, so the order
// never depends on how the driver schedules the invocations (an atomic counter's
// would, and additive blending of the listed items in another order changes the
// maps' last bits). The includer defines the three functions and calls
// compact(n) from a main() of local size 1024.
bool compact_listed(int i);
void compact_store(int slot, int i);
void compact_total(int count);

shared int compact_runs[1024];

void compact(int n) {
    int k = int(gl_LocalInvocationID.x);
    int per_run = (n + 1023) / 1024;
    int first = k * per_run, last = min(first + per_run, n);
    int own = 0;
    for (int i = first; i < last; ++i) own += compact_listed(i) ? 1 : 0;
    compact_runs[k] = own;
    barrier();
    for (int step = 1; step < 1024; step *= 2) {
        int left = k >= step ? compact_runs[k - step] : 0;
        barrier();
        compact_runs[k] += left;
        barrier();
    }
    int slot = compact_runs[k] - own;
    for (int i = first; i < last; ++i)
        if (compact_listed(i)) compact_store(slot++, i);
    if (k == 1023) compact_total(compact_runs[1023]);
}

//! A profiling aid, compiled only with the `alloc-trace` feature: the global allocator
//! wrapped with a count of live bytes and, when `MEMCONTACT_ALLOC_TRACE` is set, a table of
//! the live allocations of at least 1 MiB with the backtrace that made them. The table is
//! copied whenever the live bytes reach a new peak (in steps of 16 MiB), so that the
//! allocations alive at the peak can be listed at the end (`report`).

use std::alloc::{GlobalAlloc, Layout};
use std::cell::Cell;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicIsize, Ordering};
use std::sync::{Arc, Mutex};

pub struct Tracing<A>(pub A);

static LIVE: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);
/// The peak since the last [`report`].
static SEG_PEAK: AtomicIsize = AtomicIsize::new(0);
static ON: AtomicBool = AtomicBool::new(false);
const BIG: usize = 1 << 20;
const STEP: isize = 16 << 20;

type Table = HashMap<usize, (usize, Arc<std::backtrace::Backtrace>)>;
static TABLE: Mutex<Option<Table>> = Mutex::new(None);
static AT_PEAK: Mutex<Option<(isize, Vec<(usize, Arc<std::backtrace::Backtrace>)>)>> =
    Mutex::new(None);

thread_local! {
    static INSIDE: Cell<bool> = const { Cell::new(false) };
}

pub fn enable() {
    if std::env::var_os("MEMCONTACT_ALLOC_TRACE").is_some() {
        *TABLE.lock().unwrap() = Some(HashMap::new());
        ON.store(true, Ordering::SeqCst);
    }
}

fn guarded(f: impl FnOnce()) {
    INSIDE.with(|g| {
        if !g.get() {
            g.set(true);
            f();
            g.set(false);
        }
    });
}

fn added(ptr: *mut u8, size: usize) {
    let live = LIVE.fetch_add(size as isize, Ordering::Relaxed) + size as isize;
    let peak = PEAK.load(Ordering::Relaxed);
    if live > peak {
        PEAK.fetch_max(live, Ordering::Relaxed);
    }
    if live > SEG_PEAK.load(Ordering::Relaxed) {
        SEG_PEAK.fetch_max(live, Ordering::Relaxed);
    }
    if !ON.load(Ordering::Relaxed) || size < BIG {
        return;
    }
    guarded(|| {
        let bt = Arc::new(std::backtrace::Backtrace::force_capture());
        let mut t = TABLE.lock().unwrap();
        let Some(t) = t.as_mut() else { return };
        t.insert(ptr as usize, (size, bt));
        let mut p = AT_PEAK.lock().unwrap();
        let last = p.as_ref().map_or(0, |x| x.0);
        if live >= last + STEP {
            *p = Some((live, t.values().cloned().collect()));
        }
    });
}

fn removed(ptr: *mut u8, size: usize) {
    LIVE.fetch_sub(size as isize, Ordering::Relaxed);
    if !ON.load(Ordering::Relaxed) || size < BIG {
        return;
    }
    guarded(|| {
        if let Some(t) = TABLE.lock().unwrap().as_mut() {
            t.remove(&(ptr as usize));
        }
    });
}

unsafe impl<A: GlobalAlloc> GlobalAlloc for Tracing<A> {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let p = unsafe { self.0.alloc(l) };
        if !p.is_null() {
            added(p, l.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        let p = unsafe { self.0.alloc_zeroed(l) };
        if !p.is_null() {
            added(p, l.size());
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        removed(p, l.size());
        unsafe { self.0.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        let q = unsafe { self.0.realloc(p, l, new) };
        if !q.is_null() {
            removed(p, l.size());
            added(q, new);
        }
        q
    }
}

/// Live and peak bytes so far.
pub fn live_and_peak() -> (isize, isize) {
    (LIVE.load(Ordering::Relaxed), PEAK.load(Ordering::Relaxed))
}

/// The first frames of `bt` that are memcontact's own code (not the allocation helpers).
fn site(bt: &std::backtrace::Backtrace) -> String {
    let text = bt.to_string();
    let mut out = Vec::new();
    for line in text.lines() {
        let l = line.trim();
        let Some(name) = l.split_once(": ").map(|x| x.1) else {
            continue;
        };
        if !name.starts_with("memcontact") || name.contains("alloc_trace") {
            continue;
        }
        let short = name.rsplit_once("::h").map_or(name, |x| x.0).to_string();
        if out.last() != Some(&short) {
            out.push(short);
        }
        if out.len() == 3 {
            break;
        }
    }
    out.join(" < ")
}

/// Prints the live allocations of at least 1 MiB at the (last recorded) peak, grouped by
/// the site that made them, largest first.
pub fn report(label: &str) {
    let (live, peak) = live_and_peak();
    let seg = SEG_PEAK.swap(live, Ordering::Relaxed);
    eprintln!(
        "[alloc] {label}: live {:.1} MiB, peak since the last report {:.1} MiB, peak {:.1} MiB",
        live as f64 / 1048576.0,
        seg as f64 / 1048576.0,
        peak as f64 / 1048576.0
    );
    // MEMCONTACT_ALLOC_TRACE=phases: the list at every phase's peak, not only at the end.
    let phases = std::env::var("MEMCONTACT_ALLOC_TRACE").is_ok_and(|v| v == "phases");
    let at_end = label.starts_with("end");
    if !ON.load(Ordering::Relaxed) || !(at_end || phases && label.ends_with("finished")) {
        return;
    }
    guarded(|| {
        let p = if phases {
            AT_PEAK.lock().unwrap().take()
        } else {
            AT_PEAK.lock().unwrap().clone()
        };
        let Some((at, list)) = p else { return };
        let mut by: HashMap<String, (usize, usize)> = HashMap::new();
        for (size, bt) in &list {
            let e = by.entry(site(bt)).or_default();
            e.0 += size;
            e.1 += 1;
        }
        let mut v: Vec<_> = by.into_iter().collect();
        v.sort_by(|a, b| b.1 .0.cmp(&a.1 .0));
        let total: usize = v.iter().map(|x| x.1 .0).sum();
        eprintln!(
            "[alloc] at the peak ({:.1} MiB live): {:.1} MiB in {} allocations of >= 1 MiB",
            at as f64 / 1048576.0,
            total as f64 / 1048576.0,
            list.len()
        );
        for (s, (bytes, count)) in v {
            eprintln!(
                "[alloc]   {:9.1} MiB {:4}x  {s}",
                bytes as f64 / 1048576.0,
                count
            );
        }
    });
}

//! The one lowering of a [`Program`] to Rust: one `let` per instruction,
//! for the rigid models' functions (`emit`) and the ANCF element kernels
//! (`ancf::emit`) alike. A [`Style`] says how inputs are read, whether
//! products fuse into `mul_add`, whether values are `f64` or `Lanes<W>`
//! (`W` elements at once: constants splatted, functions the lane-wise
//! methods) and whether parts are methods or free functions.
//!
//! Long programs become several functions: rustc and LLVM are superlinear in the length of a function, and very
//! long straight-line functions can exhaust rustc's stack. A program of more
//! than [`PART_LIMIT`] instructions is cut into consecutive parts, each an
//! `#[inline(never)]` method; a temporary that is defined in one part and
//! read in a later one gets a slot in a scratch array `s` on the caller's
//! stack, so every part stays short. Outputs are stored where they are
//! computed, the part taking the function's output array ([`lower_into`]);
//! lanes, and functions lowered with [`lower`], keep their outputs in `s`
//! for the caller to read.

use super::{float, float_operand, tmp};
use crate::sym::{Op, Operand, Program, Symbol};
use proc_macro2::{Ident, Literal, TokenStream};
use quote::{format_ident, quote};
use std::collections::HashMap;

/// Instructions per part.
pub const PART_LIMIT: usize = 1500;

/// The longest program written as one part, late-scheduled, when
/// evaluated one state at a time, for forward and inverse dynamics (their
/// derivatives have [`DERIVATIVES_ONE_PART_LIMIT`]; see [`part_limit`]).
/// Measured (BENCHMARKS.md, "One function or parts"):
/// panda's inverse dynamics (1 517 instructions) about 20 % faster whole
/// than in two parts, its forward dynamics (2 285) about 8 %; arm7's
/// forward-dynamics derivatives (6 081) 4 % faster whole in blocks than in
/// parts (8 % written flat, which debug builds cannot compile).
///
/// Every `let` opens a lexical scope inside the previous one, and with
/// debug info (the default `dev` profile) LLVM walks the nested scopes
/// recursively: rustc 1.95 overflows its stack at about 2 950 of them
/// (measured on a synthetic function; arm7's derivatives written flat in
/// one part, 4 707 `let`s, did). So a function written whole is cut into
/// blocks of at most [`BLOCK_LIMIT`] instructions, each its own scope.
pub const ONE_PART_LIMIT: usize = 6500;

/// The longest derivative program written as one function (in blocks,
/// depth first: [`Schedule::DepthFirst`]) one state at a time. Measured
/// (BENCHMARKS.md, "Depth-first order for the derivatives"), each timing
/// binary in three copies so that the placement of its code in memory
/// varies: panda's derivatives (≈ 8 800 instructions) 1 466–1 594 ns whole
/// against 1 748–2 742 in six parts, the spatial 10-link chain's
/// (≈ 9 700) 1 684–1 806 against 1 732–2 021.
pub const DERIVATIVES_ONE_PART_LIMIT: usize = 10_000;

/// The most instructions of a function written whole between two block
/// boundaries: a function longer than this is written as blocks `{ … }`
/// in sequence, values that cross a block kept in a local array (which
/// release builds keep in registers), because rustc cannot compile one
/// scope of many more `let`s with debug info (see [`ONE_PART_LIMIT`]).
pub const BLOCK_LIMIT: usize = PART_LIMIT;

/// The part limit of program `p` written in style `b`: [`PART_LIMIT`],
/// but for a program of a function that gains from one part evaluated one
/// state at a time that has at most `whole` instructions
/// ([`ONE_PART_LIMIT`] for forward and inverse dynamics,
/// [`DERIVATIVES_ONE_PART_LIMIT`] for their derivatives, 0 for the rest).
/// The mass matrix stays in parts: talos' (2 993 instructions) was 15 %
/// slower in one.
pub fn part_limit(b: &Style<'_>, p: &Program, whole: usize) -> usize {
    if b.lanes.is_none() && p.instrs.len() <= whole {
        p.instrs.len().max(PART_LIMIT)
    } else {
        PART_LIMIT
    }
}

/// How a program's values are written.
pub struct Style<'a> {
    /// How each input symbol is read.
    pub input: &'a dyn Fn(&Symbol) -> TokenStream,
    /// Fuse `a·b + c` into `f64::mul_add` where the product is used only
    /// there.
    pub fma: bool,
    /// Every value is a `Lanes<W>` (`W` elements, or states, by the same
    /// straight-line code), written through this path (`Lanes` in the
    /// element kernels, `::eom_sim::Lanes` in models): constants are
    /// splatted, functions are the lane-wise methods, parts are generic in
    /// `W`.
    pub lanes: Option<TokenStream>,
    /// Parts are methods of `&self` (else free functions); with `lanes`,
    /// associated functions called through `Self::`.
    pub methods: bool,
    /// Scalar code in a crate that depends on `eom_sim`: the `sin_cos` of
    /// the inputs in one vectorised call
    /// (`::eom_sim::__private::sin_cos_lanes`).
    pub sin_cos_together: bool,
}

impl Style<'_> {
    /// A constant in operand position.
    fn constant(&self, c: f64) -> TokenStream {
        if let Some(lt) = &self.lanes {
            let c = float(c);
            quote!(#lt::<W>::splat(#c))
        } else {
            float_operand(c)
        }
    }

    /// A constant as an output value.
    fn output_constant(&self, c: f64) -> TokenStream {
        if let Some(lt) = &self.lanes {
            let c = float(c);
            quote!(#lt::<W>::splat(#c))
        } else {
            float(c)
        }
    }

    /// `f(x)` of a one-argument function.
    fn unary(&self, f: &str, x: TokenStream) -> TokenStream {
        let f = format_ident!("{f}");
        if self.lanes.is_some() {
            quote!(#x.#f())
        } else {
            quote!(f64::#f(#x))
        }
    }
}

/// An argument of a generated function.
pub struct Arg<'a> {
    /// Its name.
    pub name: &'static str,
    /// Its type.
    pub ty: TokenStream,
    /// Which symbols it carries.
    pub carries: Box<dyn Fn(&Symbol) -> bool + 'a>,
}

/// A program ready to be placed in a function.
pub struct Lowered {
    /// Statements of the function body (the instructions, or the calls of
    /// the parts).
    pub body: TokenStream,
    /// The value of each output.
    pub outputs: Vec<TokenStream>,
    /// Methods holding the parts (empty if not split).
    pub parts: TokenStream,
    /// Per argument: is it used (else its name gets a `_` prefix)?
    pub used: Vec<bool>,
    /// With a [`Dest`] ([`lower_into`]): the stores of the outputs the
    /// body has not written already (all of them for a function written
    /// flat; constants and inputs for one in parts or blocks, whose
    /// temporaries are stored where they are defined). Empty otherwise.
    pub assign: TokenStream,
}

/// Where a function's outputs go, for [`lower_into`]: a function in parts
/// or blocks stores each output where its value is computed, so no output
/// passes through the scratch array and the caller copies none of them at
/// the end (code that runs once per call, in functions that are already
/// longer than the instruction cache holds: BENCHMARKS.md, "The
/// instruction cache").
pub struct Dest<'a> {
    /// The output parameter of the function, passed on to the parts that
    /// store outputs.
    pub name: Ident,
    /// Its type, `&mut [f64; N]` or `&mut [[f64; N]; N]`.
    pub ty: TokenStream,
    /// The statements that store output `k` with value `v` (an identifier,
    /// a constant or an input).
    pub assign: Store<'a>,
}

/// The statements that store output `k` with value `v`, for [`Dest`].
pub type Store<'a> = Box<dyn Fn(usize, &TokenStream) -> TokenStream + 'a>;

impl Dest<'_> {
    /// The flat output array `name: &mut [f64; len]`, output `k` stored to
    /// `name[k]`.
    pub fn flat(name: &Ident, len: usize) -> Dest<'static> {
        let (out, len_lit) = (name.clone(), Literal::usize_unsuffixed(len));
        Dest {
            name: name.clone(),
            ty: quote!(&mut [f64; #len_lit]),
            assign: Box::new(move |k, v| {
                let k = Literal::usize_unsuffixed(k);
                quote!(#out[#k] = #v;)
            }),
        }
    }
}

impl Lowered {
    /// The argument list `name: ty, …` with unused names prefixed `_`.
    pub fn params(&self, args: &[Arg<'_>]) -> TokenStream {
        let items = args.iter().zip(&self.used).map(|(a, &used)| {
            let n = if used {
                format_ident!("{}", a.name)
            } else {
                format_ident!("_{}", a.name)
            };
            let ty = &a.ty;
            quote!(#n: #ty)
        });
        quote!(#(#items),*)
    }
}

fn reads(p: &Program, ops: &[Operand], carries: &dyn Fn(&Symbol) -> bool) -> bool {
    ops.iter()
        .any(|o| matches!(o, Operand::Var(i) if carries(&p.inputs[*i as usize])))
}

/// One statement per instruction of `p.instrs[range]`; temporaries outside
/// the range (and those listed in `store`) go through the scratch slots.
fn statements(
    b: &Style<'_>,
    p: &Program,
    range: std::ops::Range<usize>,
    slots: &HashMap<u32, usize>,
    split: bool,
    direct: &HashMap<u32, TokenStream>,
) -> TokenStream {
    // Temporaries are numbered in instruction order: the part defines
    // those from its first instruction's up to the next part's first.
    let first = p.instrs.get(range.start).map_or(0, |i| i.dst);
    let next = p.instrs.get(range.end).map_or(u32::MAX, |i| i.dst);
    let defined_here = |t: u32| !split || (first..next).contains(&t);
    let o = |x: Operand| -> TokenStream {
        match x {
            Operand::Const(n) => b.constant(n.to_f64()),
            Operand::Var(i) => (b.input)(&p.inputs[i as usize]),
            Operand::Tmp(t) if defined_here(t) => {
                let t = tmp(t);
                quote!(#t)
            }
            // Every temporary read across parts has a slot (see `lower`).
            Operand::Tmp(t) => match slots.get(&t) {
                Some(&k) => {
                    let k = Literal::usize_unsuffixed(k);
                    quote!(s[#k])
                }
                None => quote!(::core::compile_error!(
                    "eom-gen: a temporary read across parts has no slot"
                )),
            },
        }
    };
    // Products used once, by an addition in this part: fused into it.
    let fused = if b.fma {
        fusable(p, range.clone(), slots)
    } else {
        HashMap::new()
    };
    let mul_add = match &b.lanes {
        Some(lt) => quote!(#lt::mul_add),
        None => quote!(f64::mul_add),
    };
    // An operand as a function argument, negated if asked: a constant is
    // written with its sign folded in and without parentheses (rustc's
    // `unused_parens` lints `f(( -1.0 ))`; the generated code is
    // warning-free).
    let arg = |x: Operand, negate: bool| -> TokenStream {
        match x {
            Operand::Const(n) if b.lanes.is_none() => {
                let c = n.to_f64();
                float(if negate { -c } else { c })
            }
            _ => {
                let x = o(x);
                if negate { quote!(-#x) } else { x }
            }
        }
    };
    let fma = |m: u32, c: TokenStream, negate_product: bool| -> TokenStream {
        let (x, y) = fused[&m];
        let (x, y) = (arg(x, negate_product), arg(y, false));
        quote!(#mul_add(#x, #y, #c))
    };
    let is_fused = |x: Operand| matches!(x, Operand::Tmp(t) if fused.contains_key(&t));
    let mut out = TokenStream::new();
    // Scalar code: the `sin_cos` of the inputs (the joint angles) in one
    // vectorised call at the part's start, padded to a multiple of four
    // lanes, where there are two or more.
    let hoisted: Vec<(u32, Operand)> = if b.lanes.is_none() && b.sin_cos_together {
        p.instrs[range.clone()]
            .iter()
            .filter_map(|i| match i.op {
                Op::SinCos(x) if !matches!(x, Operand::Tmp(_)) => Some((i.dst, x)),
                _ => None,
            })
            .collect()
    } else {
        Vec::new()
    };
    let hoisted = if hoisted.len() >= 2 {
        hoisted
    } else {
        Vec::new()
    };
    if !hoisted.is_empty() {
        let width = hoisted.len().div_ceil(4) * 4;
        let pad = width - hoisted.len();
        let sn = hoisted.iter().map(|&(d, _)| tmp(d));
        let cs = hoisted.iter().map(|&(d, _)| tmp(d + 1));
        let xs = hoisted.iter().map(|&(_, x)| o(x));
        let blank = (0..pad).map(|_| quote!(_));
        let blank2 = (0..pad).map(|_| quote!(_));
        let zeros = (0..pad).map(|_| quote!(0.0));
        let xs2 = hoisted.iter().map(|&(_, x)| o(x));
        let zeros2 = (0..pad).map(|_| quote!(0.0));
        let width_lit = Literal::usize_unsuffixed(width);
        // The vectorised kernel only where the build has 256-bit vectors
        // (`target-cpu=native` on this machine): with SSE2 alone the
        // padded lanes cost more than the C library's calls on most
        // functions (BENCHMARKS.md, "One vectorised sin_cos"). Both
        // branches are compiled (and type-checked) in every build.
        let n = Literal::usize_unsuffixed(hoisted.len());
        out.extend(quote!(
            let ([#(#sn,)* #(#blank,)*], [#(#cs,)* #(#blank2,)*]) =
                if cfg!(target_feature = "avx2") {
                    ::eom_sim::__private::sin_cos_lanes([#(#xs,)* #(#zeros,)*])
                } else {
                    ::eom_sim::__private::sin_cos_each::<#width_lit>([#(#xs2,)* #(#zeros2,)*], #n)
                };
        ));
        for &(d, _) in &hoisted {
            for t in [d, d + 1] {
                out.extend(store(slots, direct, t, split));
            }
        }
    }
    for ins in &p.instrs[range] {
        if hoisted.iter().any(|&(d, _)| d == ins.dst) {
            continue;
        }
        let dst = tmp(ins.dst);
        let value = match ins.op {
            Op::Mul(..) if fused.contains_key(&ins.dst) => continue,
            Op::Add(Operand::Tmp(m), y) if is_fused(Operand::Tmp(m)) => {
                fma(m, arg(y, false), false)
            }
            Op::Add(x, Operand::Tmp(m)) if is_fused(Operand::Tmp(m)) => {
                fma(m, arg(x, false), false)
            }
            Op::Sub(x, Operand::Tmp(m)) if is_fused(Operand::Tmp(m)) => fma(m, arg(x, false), true),
            Op::Sub(Operand::Tmp(m), y) if is_fused(Operand::Tmp(m)) => fma(m, arg(y, true), false),
            Op::Add(x, y) => {
                let (x, y) = (o(x), o(y));
                quote!(#x + #y)
            }
            Op::Sub(x, y) => {
                let (x, y) = (o(x), o(y));
                quote!(#x - #y)
            }
            Op::Mul(x, y) => {
                let (x, y) = (o(x), o(y));
                quote!(#x * #y)
            }
            Op::Div(x, y) => {
                let (x, y) = (o(x), o(y));
                quote!(#x / #y)
            }
            Op::Neg(x) => {
                let x = o(x);
                quote!(-#x)
            }
            Op::Sqrt(x) => b.unary("sqrt", o(x)),
            Op::Sin(x) => b.unary("sin", o(x)),
            Op::Cos(x) => b.unary("cos", o(x)),
            Op::Tan(x) => b.unary("tan", o(x)),
            Op::Exp(x) => b.unary("exp", o(x)),
            Op::Ln(x) => b.unary("ln", o(x)),
            Op::Abs(x) => b.unary("abs", o(x)),
            Op::Atan2(y, x) if b.lanes.is_some() => {
                let (lt, y, x) = (&b.lanes, o(y), o(x));
                quote!(#lt::atan2(#y, #x))
            }
            Op::Atan2(y, x) => {
                let (y, x) = (o(y), o(x));
                quote!(f64::atan2(#y, #x))
            }
            Op::Select(c, x, y) if b.lanes.is_some() => {
                let (lt, c, x, y) = (&b.lanes, o(c), o(x), o(y));
                quote!(#lt::select(#c, #x, #y))
            }
            Op::Select(c, x, y) => {
                let (c, x, y) = (o(c), o(x), o(y));
                quote!(if #c > 0.0 { #x } else { #y })
            }
            Op::SinCos(x) => {
                let (sn, cs, x) = (tmp(ins.dst), tmp(ins.dst + 1), o(x));
                if b.lanes.is_some() {
                    out.extend(quote!(let (#sn, #cs) = #x.sin_cos();));
                } else {
                    out.extend(quote!(let (#sn, #cs) = f64::sin_cos(#x);));
                }
                for t in [ins.dst, ins.dst + 1] {
                    out.extend(store(slots, direct, t, split));
                }
                continue;
            }
        };
        out.extend(quote!(let #dst = #value;));
        out.extend(store(slots, direct, ins.dst, split));
    }
    out
}

/// Products `a·b` in `range` whose only use is an addition or subtraction
/// in the same range (and not an output or a value passed between parts):
/// those can become `mul_add`. Returns product temporary → `(a, b)`.
fn fusable(
    p: &Program,
    range: std::ops::Range<usize>,
    slots: &HashMap<u32, usize>,
) -> HashMap<u32, (Operand, Operand)> {
    let mut uses: HashMap<u32, usize> = HashMap::new();
    for ins in &p.instrs {
        for o in ins.op.operands() {
            if let Operand::Tmp(t) = o {
                *uses.entry(t).or_insert(0) += 1;
            }
        }
    }
    for &(_, o) in &p.outputs {
        if let Operand::Tmp(t) = o {
            *uses.entry(t).or_insert(0) += 2;
        }
    }
    let products: HashMap<u32, (Operand, Operand)> = p.instrs[range.clone()]
        .iter()
        .filter_map(|i| match i.op {
            Op::Mul(a, b) if uses.get(&i.dst) == Some(&1) && !slots.contains_key(&i.dst) => {
                Some((i.dst, (a, b)))
            }
            _ => None,
        })
        .collect();
    // Keep the products actually consumed by an addition here, at most one
    // per addition (the other operand stays a plain value).
    let mut fused = HashMap::new();
    for ins in &p.instrs[range] {
        let (x, y) = match ins.op {
            Op::Add(x, y) | Op::Sub(x, y) => (x, y),
            _ => continue,
        };
        for side in [y, x] {
            if let Operand::Tmp(t) = side
                && let Some(&ab) = products.get(&t)
            {
                fused.insert(t, ab);
                break;
            }
        }
    }
    fused
}

/// After temporary `t` is defined in a part or block: its slot, if a later
/// part reads it, and the outputs it is stored to (`direct`).
fn store(
    slots: &HashMap<u32, usize>,
    direct: &HashMap<u32, TokenStream>,
    t: u32,
    split: bool,
) -> TokenStream {
    if !split {
        return TokenStream::new();
    }
    let mut code = match slots.get(&t) {
        Some(&k) => {
            let (k, x) = (Literal::usize_unsuffixed(k), tmp(t));
            quote!(s[#k] = #x;)
        }
        None => TokenStream::new(),
    };
    if let Some(d) = direct.get(&t) {
        code.extend(d.clone());
    }
    code
}

/// Slots for the values `last_read` names (temporary → the last part that
/// reads it, `usize::MAX` for outputs), defined in the parts
/// `part_of_tmp` gives: in order of definition, each takes a slot whose
/// previous value was last read in an earlier part than its own (a value
/// read in part `k` and one stored in part `k` never share one), else a new
/// slot. Deterministic: ties broken by temporary number.
fn allocate_slots(
    last_read: &HashMap<u32, usize>,
    part_of_tmp: &HashMap<u32, usize>,
) -> HashMap<u32, usize> {
    let mut values: Vec<(usize, u32, usize)> = last_read
        .iter()
        .map(|(&t, &last)| (part_of_tmp.get(&t).copied().unwrap_or(0), t, last))
        .collect();
    values.sort_unstable();
    let mut slots = HashMap::new();
    // (last part read, slot) of the slots in use; slots free again.
    let mut busy: Vec<(usize, usize)> = Vec::new();
    let mut free: std::collections::BTreeSet<usize> = std::collections::BTreeSet::new();
    let mut count = 0;
    for (def, t, last) in values {
        busy.retain(|&(until, k)| {
            let done = until < def;
            if done {
                free.insert(k);
            }
            !done
        });
        let k = free.pop_first().unwrap_or_else(|| {
            count += 1;
            count - 1
        });
        busy.push((last, k));
        slots.insert(t, k);
    }
    slots
}

/// Lowers `p` for a function called `name` with arguments `args`, in
/// parts of at most [`PART_LIMIT`] instructions.
pub fn lower(b: &Style<'_>, p: &Program, name: &str, args: &[Arg<'_>]) -> Lowered {
    lower_parts(b, p, name, args, PART_LIMIT, None, Schedule::Late)
}

/// The order of the instructions of a function written whole, one state
/// at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Schedule {
    /// As late as their readers allow ([`Program::scheduled_late`]).
    Late,
    /// Depth first from the outputs ([`Program::scheduled_depth_first`])
    /// where the function is longer than a block, else late.
    DepthFirst,
}

/// [`lower`] in parts of at most `limit` instructions ([`part_limit`]),
/// for a function whose outputs go to `dest`: every
/// store of an output is in [`Lowered::body`] or [`Lowered::assign`] (in
/// that order), a temporary's where it is defined when the function is in
/// parts or blocks (one state at a time; lanes keep their outputs in the
/// scratch array). A function written whole has its instructions in the
/// order `schedule`.
pub fn lower_into(
    b: &Style<'_>,
    p: &Program,
    name: &str,
    args: &[Arg<'_>],
    limit: usize,
    dest: &Dest<'_>,
    schedule: Schedule,
) -> Lowered {
    lower_parts(b, p, name, args, limit, Some(dest), schedule)
}

fn lower_parts(
    b: &Style<'_>,
    p: &Program,
    name: &str,
    args: &[Arg<'_>],
    limit: usize,
    dest: Option<&Dest<'_>>,
    schedule: Schedule,
) -> Lowered {
    // One state at a time, the code waits on latency: each instruction as
    // late as its readers allow keeps fewer values live (BENCHMARKS.md,
    // "Sums as trees"). Measured to pay in functions of one part only
    // (arm7's forward dynamics 182 → 169 ns; its derivatives, four parts,
    // 1050 → 1200 ns), and not in lanes, which are bound by throughput.
    // A derivative function written whole in blocks spills most of all:
    // depth first it keeps fewer values live (BENCHMARKS.md, "Depth-first
    // order for the derivatives").
    let ordered;
    let p = if b.lanes.is_none() && p.instrs.len() <= limit {
        ordered = if schedule == Schedule::DepthFirst && p.instrs.len() > BLOCK_LIMIT {
            p.scheduled_depth_first()
        } else {
            p.scheduled_late(limit)
        };
        &ordered
    } else {
        p
    };
    let used: Vec<bool> = args
        .iter()
        .map(|a| p.inputs.iter().any(|s| (a.carries)(s)))
        .collect();
    let output = |o: Operand, slots: &HashMap<u32, usize>, split: bool| match o {
        Operand::Const(n) => b.output_constant(n.to_f64()),
        Operand::Var(i) => (b.input)(&p.inputs[i as usize]),
        Operand::Tmp(t) => match slots.get(&t) {
            Some(&k) if split => {
                let k = Literal::usize_unsuffixed(k);
                quote!(s[#k])
            }
            _ => {
                let t = tmp(t);
                quote!(#t)
            }
        },
    };
    // Chunks: parts (functions of their own), or, for a function written
    // whole that is longer than a block, blocks of it.
    let blocks = b.lanes.is_none() && p.instrs.len() <= limit && p.instrs.len() > BLOCK_LIMIT;
    // The stores of the outputs `dest` takes that are not temporaries
    // stored where they are defined (`direct`).
    let assign_rest = |direct: &HashMap<u32, TokenStream>, slots: &HashMap<u32, usize>, split| {
        let mut code = TokenStream::new();
        if let Some(d) = dest {
            for (k, &(_, o)) in p.outputs.iter().enumerate() {
                if !matches!(o, Operand::Tmp(t) if direct.contains_key(&t)) {
                    code.extend((d.assign)(k, &output(o, slots, split)));
                }
            }
        }
        code
    };
    if p.instrs.len() <= limit && !blocks {
        let slots = HashMap::new();
        let direct = HashMap::new();
        return Lowered {
            body: statements(b, p, 0..p.instrs.len(), &slots, false, &direct),
            outputs: p
                .outputs
                .iter()
                .map(|&(_, o)| output(o, &slots, false))
                .collect(),
            parts: TokenStream::new(),
            used,
            assign: assign_rest(&direct, &slots, false),
        };
    }
    // Outputs stored where their temporaries are defined, one state at a
    // time with a destination; with lanes, or without one, through slots.
    let mut direct: HashMap<u32, TokenStream> = HashMap::new();
    if let Some(d) = dest.filter(|_| b.lanes.is_none()) {
        for (k, &(_, o)) in p.outputs.iter().enumerate() {
            if let Operand::Tmp(t) = o {
                let v = tmp(t);
                direct
                    .entry(t)
                    .or_default()
                    .extend((d.assign)(k, &quote!(#v)));
            }
        }
    }
    // Part (or block) of each instruction, and of each temporary's
    // definition.
    let chunk = if blocks { BLOCK_LIMIT } else { limit };
    let parts: Vec<std::ops::Range<usize>> = (0..p.instrs.len())
        .step_by(chunk)
        .map(|s| s..(s + chunk).min(p.instrs.len()))
        .collect();
    let mut part_of_tmp: HashMap<u32, usize> = HashMap::new();
    for (k, r) in parts.iter().enumerate() {
        for ins in &p.instrs[r.clone()] {
            part_of_tmp.insert(ins.dst, k);
            if let Op::SinCos(_) = ins.op {
                part_of_tmp.insert(ins.dst + 1, k);
            }
        }
    }
    // Slots: temporaries read in a later part, and temporary outputs.
    // Each is live from its defining part to the last part that reads it
    // (outputs to the end); a slot is reused by a value defined in a part
    // after the last read of its previous value, so the scratch array the
    // caller zeroes on every call is as short as the most values live
    // across one part boundary, not the count of all of them.
    let mut last_read: HashMap<u32, usize> = HashMap::new();
    for (k, r) in parts.iter().enumerate() {
        for ins in &p.instrs[r.clone()] {
            for o in ins.op.operands() {
                if let Operand::Tmp(t) = o
                    && part_of_tmp.get(&t).is_some_and(|&d| d < k)
                {
                    let last = last_read.entry(t).or_insert(k);
                    *last = (*last).max(k);
                }
            }
        }
    }
    for &(_, o) in &p.outputs {
        if let Operand::Tmp(t) = o
            && !direct.contains_key(&t)
        {
            last_read.insert(t, usize::MAX);
        }
    }
    let slots = allocate_slots(&last_read, &part_of_tmp);
    let ns = Literal::usize_unsuffixed(slots.values().map(|&k| k + 1).max().unwrap_or(1));
    if blocks {
        // One function, its blocks in sequence, values that cross a block
        // in a local array (which the optimiser keeps in registers: all
        // its indices are constants).
        let bodies = parts
            .iter()
            .map(|r| statements(b, p, r.clone(), &slots, true, &direct));
        let scratch = if slots.is_empty() {
            TokenStream::new()
        } else {
            quote!(let mut s = [0.0f64; #ns];)
        };
        return Lowered {
            body: quote! {
                #scratch
                #({ #bodies })*
            },
            outputs: p
                .outputs
                .iter()
                .map(|&(_, o)| output(o, &slots, true))
                .collect(),
            parts: TokenStream::new(),
            used,
            assign: assign_rest(&direct, &slots, true),
        };
    }
    let mut methods = TokenStream::new();
    let mut calls = TokenStream::new();
    for (k, r) in parts.iter().enumerate() {
        let fname: Ident = format_ident!("{name}_part{k}");
        let ops: Vec<Operand> = p.instrs[r.clone()]
            .iter()
            .flat_map(|i| i.op.operands())
            .collect();
        let params = args.iter().map(|a| {
            let n = if reads(p, &ops, &*a.carries) {
                format_ident!("{}", a.name)
            } else {
                format_ident!("_{}", a.name)
            };
            let ty = &a.ty;
            quote!(#n: #ty)
        });
        let body = statements(b, p, r.clone(), &slots, true, &direct);
        // The output parameter, for a part that stores outputs.
        let stores = p.instrs[r.clone()].iter().any(|i| {
            direct.contains_key(&i.dst)
                || (matches!(i.op, Op::SinCos(_)) && direct.contains_key(&(i.dst + 1)))
        });
        // The scratch array, for a part that reads or stores a slot.
        let first = p.instrs[r.start].dst;
        let uses_s = p.instrs[r.clone()].iter().any(|i| {
            slots.contains_key(&i.dst)
                || (matches!(i.op, Op::SinCos(_)) && slots.contains_key(&(i.dst + 1)))
                || i.op
                    .operands()
                    .any(|o| matches!(o, Operand::Tmp(t) if t < first))
        });
        let s_name = if uses_s { quote!(s) } else { quote!(_s) };
        let (out_param, out_arg) = match dest {
            Some(d) if stores => {
                let (n, ty) = (&d.name, &d.ty);
                (quote!(, #n: #ty), quote!(, #n))
            }
            _ => (TokenStream::new(), TokenStream::new()),
        };
        let doc = format!(
            " Part {} of {} of `{name}` (instructions {}–{}).",
            k + 1,
            parts.len(),
            r.start,
            r.end - 1
        );
        let names = args.iter().map(|a| format_ident!("{}", a.name));
        if let Some(lt) = &b.lanes {
            methods.extend(quote! {
                #[doc = #doc]
                #[inline(never)]
                fn #fname<const W: usize>(#(#params,)* s: &mut [#lt<W>; #ns]) {
                    #body
                }
            });
        } else if b.methods {
            methods.extend(quote! {
                #[doc = #doc]
                #[inline(never)]
                fn #fname(&self, #(#params,)* #s_name: &mut [f64; #ns] #out_param) {
                    #body
                }
            });
        } else {
            methods.extend(quote! {
                #[doc = #doc]
                #[inline(never)]
                fn #fname(#(#params,)* #s_name: &mut [f64; #ns] #out_param) {
                    #body
                }
            });
        }
        calls.extend(if b.methods && b.lanes.is_some() {
            quote!(Self::#fname(#(#names,)* &mut s);)
        } else if b.methods {
            quote!(self.#fname(#(#names,)* &mut s #out_arg);)
        } else {
            quote!(#fname(#(#names,)* &mut s #out_arg);)
        });
    }
    let init = if let Some(lt) = &b.lanes {
        quote!(#lt::<W>::splat(0.0))
    } else {
        quote!(0.0f64)
    };
    Lowered {
        body: quote! {
            let mut s = [#init; #ns];
            #calls
        },
        outputs: p
            .outputs
            .iter()
            .map(|&(_, o)| output(o, &slots, true))
            .collect(),
        parts: methods,
        used: vec![true; args.len()],
        assign: assign_rest(&direct, &slots, true),
    }
}

/// The program's [`Product`](crate::sym::Product)s on the array `out`
/// (its outputs, already assigned, the blocks `B` holding the gradients):
/// per product, `A` read into a local array, then each row of `−A B`
/// summed over `k` along the rows of the blocks as they lie in `out`
/// (`r[j] −= a_ik b_kj`, or `mul_add` with FMA; loops the compiler runs
/// in SIMD lanes) into a local result, which is written back at the end.
pub fn products(b: &Style<'_>, p: &Program, out: &TokenStream) -> TokenStream {
    let idx = Literal::usize_unsuffixed;
    let (ty, zero) = match &b.lanes {
        Some(lt) => (quote!(#lt<W>), quote!(#lt::<W>::splat(0.0))),
        None => (quote!(f64), quote!(0.0)),
    };
    let update = if b.fma {
        match &b.lanes {
            Some(lt) => quote!(*x = #lt::mul_add(-*m, *y, *x)),
            None => quote!(*x = f64::mul_add(-*m, *y, *x)),
        }
    } else if b.lanes.is_some() {
        quote!(*x = *x - *m * *y)
    } else {
        quote!(*x -= *m * *y)
    };
    let mut code = TokenStream::new();
    for pr in &p.products {
        let (n, w) = (idx(pr.n), idx(pr.width()));
        let a0 = idx(pr.a);
        let mut acc = TokenStream::new();
        let mut write = TokenStream::new();
        let mut offset = 0;
        for &(start, cols) in &pr.blocks {
            let (c, o, e) = (idx(cols), idx(offset), idx(offset + cols));
            let (s, end) = (idx(start), idx(start + pr.n * cols));
            // Row `k` of the block, `start + k·cols ..`, with no `0 +`
            // (clippy's `identity_op`; generated code is lint-free).
            let row = if start == 0 {
                quote!(k * #c)
            } else {
                quote!(#s + k * #c)
            };
            acc.extend(quote! {
                for (x, y) in rrow[#o..#e].iter_mut().zip(&#out[#row..#row + #c]) {
                    #update;
                }
            });
            write.extend(quote! {
                for (orow, r) in #out[#s..#end].chunks_exact_mut(#c).zip(&res) {
                    orow.copy_from_slice(&r[#o..#e]);
                }
            });
            offset += cols;
        }
        code.extend(quote! {
            {
                let a: [[#ty; #n]; #n] =
                    ::core::array::from_fn(|i| ::core::array::from_fn(|k| #out[#a0 + i * #n + k]));
                let mut res = [[#zero; #w]; #n];
                for (arow, rrow) in a.iter().zip(res.iter_mut()) {
                    for (k, m) in arow.iter().enumerate() {
                        #acc
                    }
                }
                #write
            }
        });
    }
    code
}

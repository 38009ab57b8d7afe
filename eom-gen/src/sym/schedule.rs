//! The order in which a program's instructions are written out.
//!
//! Lowering leaves each instruction where its expression was first met,
//! so a value is often computed long before the one instruction that
//! reads it, and the compiler keeps it in a register or spills it all the
//! way. Reordering changes no value (every instruction computes the same
//! operation on the same operands) but shortens what is live at once.

use super::balance::latency;
use super::program::{Operand, Program};

impl Program {
    /// The program with its instructions as late as their readers allow
    /// under the latency model of [`Program::balance_sums`] (latest start
    /// = length of the critical path − the longest path from the
    /// instruction to the end), ties in program order, each instruction
    /// kept within its block of `window` consecutive instructions, and the
    /// temporaries renumbered in the new order. The blocks are the parts a
    /// long function is cut into (`emit::lower`), so no value moves from
    /// one part to another. The values are those of `self`, bit for bit.
    pub fn scheduled_late(&self, window: usize) -> Program {
        let n = self.instrs.len();
        let def_at = self.definitions();
        // Longest path from each instruction to the end, itself included.
        let mut height = vec![0u32; n];
        for k in (0..n).rev() {
            let ins = self.instrs[k];
            height[k] += latency(&ins.op);
            for o in ins.op.operands() {
                if let Operand::Tmp(t) = o {
                    let d = def_at[t as usize];
                    height[d] = height[d].max(height[k]);
                }
            }
        }
        let critical = height.iter().copied().max().unwrap_or(0);
        let mut order: Vec<usize> = (0..n).collect();
        // A reader's latest start is at least its operand's plus the
        // operand's latency (≥ 1), so sorting by it within a block keeps
        // every operand before its readers.
        order.sort_by_key(|&k| (k / window.max(1), critical - height[k], k));
        let mut p = self.clone();
        p.instrs = order.into_iter().map(|k| self.instrs[k]).collect();
        p.remove_dead();
        p
    }

    /// The instruction that defines each temporary (`usize::MAX` for a
    /// number no instruction defines).
    fn definitions(&self) -> Vec<usize> {
        let mut def_at = vec![usize::MAX; self.n_tmps as usize + 1];
        for (k, ins) in self.instrs.iter().enumerate() {
            for r in 0..ins.op.results() {
                def_at[ins.dst as usize + r as usize] = k;
            }
        }
        def_at
    }

    /// The program with its instructions in depth-first order from the
    /// outputs: each output's instructions written just before it, every
    /// instruction right after its operands, the operand on the longer
    /// path from the inputs first (Sethi and Ullman's order for trees), a
    /// value shared by later outputs where it is first needed; the
    /// temporaries renumbered in the new order. The values are those of
    /// `self`, bit for bit.
    ///
    /// Where [`Program::scheduled_late`] shortens the wait on latency, this
    /// order keeps fewer values live at once, which is what a long
    /// function that spills needs: its spills and reloads are most of its
    /// machine code (arm7's derivatives, 57 KB, 39 % of the instructions
    /// `vmovsd`), and code longer than the instruction cache is fetched
    /// again on every call (BENCHMARKS.md, "Depth-first order for the
    /// derivatives").
    pub fn scheduled_depth_first(&self) -> Program {
        let n = self.instrs.len();
        let def_at = self.definitions();
        // The instruction defining a temporary operand.
        let def = |o: Operand| match o {
            Operand::Tmp(t) => def_at.get(t as usize).copied().filter(|&d| d < n),
            _ => None,
        };
        let operand_defs = |k: usize| {
            self.instrs[k]
                .op
                .operands()
                .filter_map(def)
                .collect::<Vec<usize>>()
        };
        // Longest path from the inputs to each instruction.
        let mut depth = vec![0u32; n];
        for k in 0..n {
            depth[k] = 1 + operand_defs(k).iter().map(|&d| depth[d]).max().unwrap_or(0);
        }
        let mut done = vec![false; n];
        let mut order = Vec::with_capacity(n);
        let roots = self.outputs.iter().filter_map(|&(_, o)| def(o));
        let mut stack: Vec<(usize, bool)> = Vec::new();
        for root in roots {
            stack.push((root, false));
            while let Some((k, expanded)) = stack.pop() {
                if done[k] {
                    continue;
                }
                if expanded {
                    done[k] = true;
                    order.push(k);
                    continue;
                }
                stack.push((k, true));
                let mut ops = operand_defs(k);
                ops.retain(|&d| !done[d]);
                // The deeper operand is pushed last, so written first.
                ops.sort_by_key(|&d| depth[d]);
                stack.extend(ops.into_iter().map(|d| (d, false)));
            }
        }
        let mut p = self.clone();
        p.instrs = order.into_iter().map(|k| self.instrs[k]).collect();
        p.remove_dead();
        p
    }
}

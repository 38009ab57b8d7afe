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
        let mut def_at = vec![usize::MAX; self.n_tmps as usize + 2];
        for (k, ins) in self.instrs.iter().enumerate() {
            def_at[ins.dst as usize] = k;
            def_at[ins.dst as usize + 1] = k;
        }
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
}

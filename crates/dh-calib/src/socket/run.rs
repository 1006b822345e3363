//! A socket calibration run: the model, the calibration and validation contacts, the scales
//! and the options, and the fits and reports of each step.

use super::*;

/// Everything the steps share.
pub(super) struct Run<'a> {
    pub(super) model: Model,
    pub(super) cal: Split2,
    pub(super) val: Split2,
    pub(super) scales: Vec<f64>,
    pub(super) options: &'a CalibrationOptions,
    pub(super) sigma_point: f64,
}

impl Run<'_> {
    pub(super) fn problem(&self, sigma_point: f64) -> SocketProblem<'_> {
        SocketProblem {
            model: &self.model,
            contacts: &self.cal.contacts,
            constraints: &self.cal.constraints,
            sockets: self.cal.names.len(),
            sigma_point,
        }
    }

    /// Fits `free` from `x0`, re-estimating the contact noise that weights the distances.
    pub(super) fn fit(&mut self, x0: &[f64], free: &[usize]) -> Result<FitOutcome, CalibError> {
        let mut x = x0.to_vec();
        let given = self.options.sigma;
        let mut sigma = match given {
            Some(s) => s,
            None => sigma_of(&self.problem(1.0), x0, free.len()),
        };
        let mut outcome = None;
        for _ in 0..SIGMA_PASSES {
            let problem = self.problem(sigma);
            let o = fit::solve(&problem, &x, free, &self.scales, &self.options.fit)?;
            x.clone_from(&o.x);
            outcome = Some(o);
            if given.is_some() {
                break;
            }
            let next = sigma_of(&problem, &x, free.len());
            let change = (next / sigma - 1.0).abs();
            sigma = next;
            if change < SIGMA_CHANGE {
                break;
            }
        }
        self.sigma_point = sigma;
        outcome.ok_or_else(|| CalibError::NoConvergence {
            what: "socket fit".into(),
        })
    }

    pub(super) fn step(
        &mut self,
        label: &str,
        x0: &[f64],
        free: &[usize],
    ) -> Result<(FitOutcome, SocketStep), CalibError> {
        let outcome = self.fit(x0, free)?;
        let problem = self.problem(self.sigma_point);
        let d: Vec<f64> = positions(&self.model, &outcome.x, &self.cal.contacts)
            .iter()
            .zip(&self.cal.contacts)
            .map(|(p, c)| (p - problem.socket_at(&outcome.x, c.socket)).norm())
            .collect();
        let cal = Stats::of(&d).unwrap_or(Stats {
            rms: 0.0,
            mean: 0.0,
            max: 0.0,
            count: 0,
        });
        let val = self.held_out(&outcome.x);
        let report = SocketStep {
            label: label.into(),
            rms: cal.rms,
            mean: cal.mean,
            max: cal.max,
            val_rms: val.map(|v| v.rms),
            free: free.len(),
            iterations: outcome.iterations,
            termination: outcome.termination,
        };
        Ok((outcome, report))
    }

    /// Distances of the validation contacts to their socket's mean (metres).
    pub(super) fn held_out_distances(&self, x: &[f64]) -> Vec<f64> {
        distances_to_means(&self.model, x, &self.val)
    }

    /// Their statistics, `None` without validation contacts.
    pub(super) fn held_out(&self, x: &[f64]) -> Option<Stats> {
        Stats::of(&self.held_out_distances(x))
    }

    /// Scores the model's effect `e` at `x` with `free` estimated (see [`diagnose_sockets`]):
    /// the QR factor of the scaled columns `[free, effect]` gives the first-order SSR reduction
    /// (the effect's part of `Qᵀr`, m²) and the independence (smallest singular value of the
    /// effect's block of `R` over its largest column norm).
    pub(super) fn score(
        &self,
        x: &[f64],
        free: &[usize],
        e: usize,
    ) -> Result<CandidateReport, CalibError> {
        let (label, cols): (String, Vec<usize>) = match self.model.effects().get(e) {
            Some((eff, r)) => (eff.label(), r.clone().collect()),
            None => (String::new(), Vec::new()),
        };
        let p = free.len();
        let k = cols.len();
        let mut columns = free.to_vec();
        columns.extend(&cols);
        let f = fit::factor(&self.problem(self.sigma_point), x, &columns, &self.scales)?;
        let big = (p..p + k).map(|j| f.r.column(j).norm()).fold(0.0, f64::max);
        let inert = k == 0 || big <= 0.0;
        let smin = if inert {
            0.0
        } else {
            f.r.view((p, p), (k, k))
                .clone_owned()
                .singular_values()
                .min()
        };
        let independence = if inert { 0.0 } else { smin / big };
        let aliased = !inert && independence < ALIAS_SINE;
        let reduction: f64 = (p..p + k).map(|i| f.qtr[i] * f.qtr[i]).sum();
        Ok(CandidateReport {
            label,
            parameters: k,
            score: if aliased || inert { 0.0 } else { reduction },
            independence,
            val_rms: None,
            reason: None,
            status: if inert {
                CandidateStatus::Inert
            } else if aliased {
                CandidateStatus::Aliased
            } else {
                CandidateStatus::NotSelected
            },
        })
    }

    pub(super) fn consistency(&self, label: &str, x: &[f64]) -> Option<ConsistencyStep> {
        let c = &self.cal;
        let v = &self.val;
        Some(ConsistencyStep {
            label: label.into(),
            train: consistency(&self.model, x, &c.contacts, &c.constraints, c.names.len())?,
            test: consistency(&self.model, x, &v.contacts, &v.constraints, v.names.len()),
        })
    }

    /// Identifiability of `columns` at `x`: free and fixed (see [`fit::identifiability`]), with
    /// the device frame fixed first (gauge, see the module docs) and the sockets last.
    pub(super) fn identify(
        &self,
        x: &[f64],
        columns: &[usize],
    ) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
        let problem = self.problem(self.sigma_point);
        let f = fit::factor(&problem, x, columns, &self.scales)?;
        let prio_model = self.model.priorities();
        let prio: Vec<u32> = columns
            .iter()
            .map(|&c| match self.model.parameters().get(c).map(|p| p.block) {
                Some(Block::Device) => 0,
                Some(_) => prio_model[c],
                None => 5,
            })
            .collect();
        let id = fit::identifiability(
            &f.r,
            &vec![1.0; columns.len()],
            &prio,
            self.options.fit.rank_tolerance,
        )?;
        let free = id.free.iter().map(|&i| columns[i]).collect();
        let fixed = id
            .fixed
            .into_iter()
            .map(|f| fit::Fixed {
                index: columns[f.index],
                aliases: f.aliases.iter().map(|&a| columns[a]).collect(),
                combination: Vec::new(),
            })
            .collect();
        Ok((free, fixed))
    }

    pub(super) fn name_of(&self, c: usize) -> String {
        match self.model.parameters().get(c) {
            Some(p) => p.name.clone(),
            None => {
                let s = c - self.model.parameter_count();
                let axis = ["x", "y", "z"][s % 3];
                let name = self.cal.names.get(s / 3).map_or("?", String::as_str);
                format!("socket.{name}.{axis}")
            }
        }
    }
}

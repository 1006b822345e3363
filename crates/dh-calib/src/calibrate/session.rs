//! A calibration session: the model, the prepared data and the options, and the steps run on
//! them (`nominal`, identifiability, `geometric`, `effects`; module docs, steps 2 to 5).

use super::*;

/// Everything the steps of one calibration share: the samples, the model (with every effect
/// that any step may free), the validation scheme.
pub(crate) struct Session<'a> {
    pub(crate) model: Model,
    pub(crate) prep: Prepared,
    pub(crate) scales: Vec<f64>,
    pub(crate) options: &'a CalibrationOptions,
    pub(crate) validation: Validation,
    pub(crate) notes: Vec<String>,
    pub(super) measured: Vec<bool>,
    pub(super) device_nominal: Isometry3<f64>,
    pub(super) targets_nominal: Vec<Vector3<f64>>,
    /// The name of every session of the data (see [`crate::sessions`]).
    pub(super) session_names: Vec<String>,
    /// Beyond [`CV_TRAINING_MAX`] calibration samples, about that many evenly spaced ones
    /// within each session and target (see [`coarse_subset`]; indices
    /// into `prep.cal`): the closed-form start, each step's identifiability and each fit's
    /// first iterations use them, and the fit of every sample starts where theirs ends (one
    /// or two passes over millions of samples instead of one per iteration). Empty for
    /// smaller sets, which are fitted as they are.
    pub(super) coarse: Vec<usize>,
    /// The position residuals of `prep.cal` at the last point asked for
    /// ([`Session::position_residuals`]).
    pub(super) residuals_at: ResidualsAt,
    /// The points the outlier screen left out, when a diagnosis judges them against its
    /// candidates' fits ([`LeftOut`]; `None` otherwise).
    pub(crate) left_out: Option<LeftOut>,
}

/// What [`Session::identify_factored`] finds: the free and held columns, and the factor it
/// decided on (of all calibration samples) when there is no coarse subset.
pub(crate) type Identified = (Vec<usize>, Vec<fit::Fixed>, Option<fit::Factor>);

/// The chain of each target of `data` in `tree` (see [`CalibrationOptions::target_branches`]).
pub(super) fn target_chains(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<Vec<(String, usize)>, CalibError> {
    data.targets
        .iter()
        .map(|t| {
            if tree.branches().is_empty() {
                return Ok((t.clone(), 0));
            }
            let branch = options
                .target_branches
                .iter()
                .find(|(target, _)| target == t)
                .map_or(t.as_str(), |(_, b)| b.as_str());
            tree.branch_index(branch)
                .map(|b| (t.clone(), b))
                .ok_or_else(|| CalibError::BadOption {
                    what: format!("target '{t}'"),
                    reason: format!(
                        "expected a branch of the tree ({}), found '{branch}'",
                        tree.branches()
                            .iter()
                            .map(|b| b.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })
        })
        .collect()
}

impl<'a> Session<'a> {
    /// Prepares the samples, builds the model of `tree` with `effects` (their parameters start
    /// at zero and are not estimated until a step frees them) and finds the closed-form start;
    /// `sequence` places the samples in a longer sequence (see [`prepare`]).
    pub(crate) fn new(
        tree: &DhTree,
        data: &Measurements,
        options: &'a CalibrationOptions,
        effects: &[Arc<dyn Effect>],
        sequence: Option<&[SampleContext]>,
    ) -> Result<Session<'a>, CalibError> {
        crate::sessions::check(data)?;
        let directions = effects.iter().any(|e| e.uses_sequence());
        let prep = prepare(tree, data, sequence, directions)?;
        if prep.cal.len() < 3 {
            return Err(CalibError::TooFewSamples {
                what: "calibration".into(),
                needed: 3,
                found: prep.cal.len(),
            });
        }
        let mut prep = prep;
        if !directions {
            // No effect reads the direction of motion: 8 bytes per joint and sample freed.
            for o in prep.cal.iter_mut().chain(prep.val.iter_mut()) {
                o.context.direction = Vec::new();
            }
        }
        let chains = target_chains(tree, data, options)?;
        let mut model = Model::new_tree(tree, &chains, &options.model)?;
        crate::sessions::add_blocks(&mut model, data, &prep.cal);
        add_target_orientations(&mut model, &prep.cal);
        for e in effects {
            model.add_effect(e.clone())?;
        }
        let scales = model.scales();
        let x = vec![0.0; model.parameter_count()];
        let coarse = if prep.cal.len() > CV_TRAINING_MAX {
            coarse_subset(&prep.cal, CV_TRAINING_MAX)
        } else {
            Vec::new()
        };
        if coarse.is_empty() {
            initialise(&mut model, &x, &prep.cal, options)?;
        } else {
            let sample: Vec<Observed> = coarse.iter().map(|&i| prep.cal[i].clone()).collect();
            initialise(&mut model, &x, &sample, options)?;
        }
        orient_targets(&mut model, &x, &prep.cal);
        let validation = if !prep.val.is_empty() {
            Validation::Split {
                samples: prep.val.len(),
            }
        } else if prep.group_count >= 2 && options.folds >= 2 {
            Validation::CrossValidation {
                folds: options.folds.min(prep.group_count),
                groups: prep.group_count,
                training_subsample: (prep.cal.len() > CV_TRAINING_MAX).then_some(CV_TRAINING_MAX),
                one_step: false,
            }
        } else {
            Validation::None
        };
        let mut notes = Vec::new();
        // Targets never measured stay where they are and are reported as fixed.
        let mut measured = vec![false; model.targets().len()];
        for o in &prep.cal {
            if let Observation::Point { target, .. } | Observation::TargetPose { target, .. } =
                &o.observation
            {
                measured[*target] = true;
            }
        }
        for (k, m) in measured.iter().enumerate() {
            if !m {
                let validated = prep.val.iter().filter(
                    |o| matches!(o.observation, Observation::Point { target, .. } if target == k),
                );
                let n = validated.count();
                notes.push(if n > 0 {
                    format!(
                        "target '{}' has no calibration sample; its position on the tip is located from its own {n} validation samples (3 parameters) before they are compared",
                        model.targets()[k].0
                    )
                } else {
                    format!(
                        "target '{}' has no calibration sample; its position is not estimated",
                        model.targets()[k].0
                    )
                });
            }
        }
        notes.extend(crate::sessions::unseen_notes(data, &prep));
        if !coarse.is_empty() {
            notes.push(format!(
                "{} calibration samples: the closed-form start, the identifiability tests and \
                 each fit's first iterations use {} of them, evenly spaced within each session and \
                 target; every fit then \
                 converges on all of them (its figures and standard errors are of all samples)",
                prep.cal.len(),
                coarse.len()
            ));
        }
        let device_nominal = model.device();
        let targets_nominal = model.targets().iter().map(|t| t.1).collect();
        Ok(Session {
            session_names: (0..data.session_count())
                .map(|s| data.session_name(s))
                .collect(),
            model,
            prep,
            scales,
            options,
            validation,
            notes,
            measured,
            device_nominal,
            targets_nominal,
            coarse,
            residuals_at: ResidualsAt::default(),
            left_out: None,
        })
    }

    /// The position residuals (model minus measured, device frame, metres) of every
    /// calibration sample at `x`, computed once per point for the passes that read them
    /// there (see [`ResidualsAt`]).
    pub(crate) fn position_residuals(&self, x: &[f64]) -> Arc<Vec<Vector3<f64>>> {
        self.residuals_at.of(&self.model, x, &self.prep.cal)
    }

    /// Fits `free` from `x0` and reports the step; `previous` is the step before it.
    pub(crate) fn step(
        &self,
        label: &str,
        x0: &[f64],
        free: &[usize],
        previous: Option<&StepReport>,
    ) -> Result<StepResult, CalibError> {
        self.step_with(label, x0, free, previous, Folds::Refit)
    }

    /// Held-out distances at the fit `x` of `free` (see [`held_out`]), the folds of a
    /// cross-validation refitted or stepped once ([`Folds`]).
    pub(crate) fn held_out_with(
        &self,
        x: &[f64],
        free: &[usize],
        folds: Folds,
    ) -> Result<HeldOut, CalibError> {
        match (&self.validation, folds) {
            (_, Folds::Later) => Ok(HeldOut::default()),
            (Validation::CrossValidation { folds: k, .. }, Folds::OneStep) => {
                super::one_step::one_step_cross_validation(
                    &self.model,
                    &self.prep,
                    *k,
                    x,
                    free,
                    &self.scales,
                    self.options.fit.rank_tolerance,
                )
            }
            _ => held_out(
                &self.model,
                &self.prep,
                &self.validation,
                x,
                free,
                &self.scales,
                &self.options.fit,
            ),
        }
    }

    /// [`Session::step`] with the held-out distances computed as `folds` says.
    pub(crate) fn step_with(
        &self,
        label: &str,
        x0: &[f64],
        free: &[usize],
        previous: Option<&StepReport>,
        folds: Folds,
    ) -> Result<StepResult, CalibError> {
        self.step_from(label, x0, free, previous, folds, None)
    }

    /// [`Session::step_with`] given the factor of `free` at `x0` over all calibration samples
    /// when the caller has it (from [`Session::identify_factored`]).
    pub(crate) fn step_from(
        &self,
        label: &str,
        x0: &[f64],
        free: &[usize],
        previous: Option<&StepReport>,
        folds: Folds,
        first: Option<fit::Factor>,
    ) -> Result<StepResult, CalibError> {
        let problem = SessionProblem { session: self };
        let start = if self.coarse.is_empty() {
            x0.to_vec()
        } else {
            let sample = SubsetProblem {
                model: &self.model,
                observations: &self.prep.cal,
                subset: &self.coarse,
            };
            fit::solve_point_from(&sample, x0, free, &self.scales, &self.options.fit, None)?
        };
        // A coarse start moves away from `x0`, where the given factor is.
        let first = first.filter(|_| self.coarse.is_empty());
        let outcome = fit::solve_from(
            &problem,
            &start,
            free,
            &self.scales,
            &self.options.fit,
            first,
        )?;
        let cal: Vec<f64> = self
            .position_residuals(&outcome.x)
            .iter()
            .map(|r| r.norm())
            .collect();
        let cal = Stats::of(&cal);
        let held = self.held_out_with(&outcome.x, free, folds)?;
        let val = Stats::of(&held.distances);
        let cal = cal.unwrap_or(Stats {
            rms: 0.0,
            mean: 0.0,
            max: 0.0,
            count: 0,
        });
        let report = StepReport {
            label: label.into(),
            rms_before: previous.map(|p| p.rms),
            val_rms_before: previous.and_then(|p| p.val_rms),
            rms: cal.rms,
            mean: cal.mean,
            max: cal.max,
            val_rms: val.map(|v| v.rms),
            val_mean: val.map(|v| v.mean),
            val_max: val.map(|v| v.max),
            val_angle_rms: held.angle_rms(),
            free: free.len(),
            angle_rms: angle_rms(&self.model, &outcome.x, &self.prep.cal),
            iterations: outcome.iterations,
            termination: outcome.termination,
            fixed: Vec::new(),
        };
        Ok(StepResult {
            outcome,
            report,
            held_out: held,
        })
    }

    /// Identifiability of `columns` at `x` (see [`identify`]).
    pub(crate) fn identify(
        &self,
        x: &[f64],
        columns: &[usize],
    ) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
        if self.coarse.is_empty() {
            return identify(
                &self.model,
                &self.prep.cal,
                x,
                columns,
                &self.scales,
                self.options,
            );
        }
        let sample = SubsetProblem {
            model: &self.model,
            observations: &self.prep.cal,
            subset: &self.coarse,
        };
        identify_in(&sample, &self.model, x, columns, &self.scales, self.options)
    }

    /// [`Session::identify`], with the factor it decided on when that is of all calibration
    /// samples (no coarse subset): a step of the same columns from `x` starts from it.
    pub(crate) fn identify_factored(
        &self,
        x: &[f64],
        columns: &[usize],
    ) -> Result<Identified, CalibError> {
        if !self.coarse.is_empty() {
            let (free, fixed) = self.identify(x, columns)?;
            return Ok((free, fixed, None));
        }
        let problem = ModelProblem {
            model: &self.model,
            observations: &self.prep.cal,
        };
        let (free, fixed, f) = identify_factored_in(
            &problem,
            &self.model,
            x,
            columns,
            &self.scales,
            self.options,
        )?;
        Ok((free, fixed, Some(f)))
    }

    /// Names of `fixed` parameters and their aliases, for a report.
    pub(crate) fn named(&self, fixed: &[fit::Fixed]) -> Vec<FixedParameter> {
        let params = self.model.parameters();
        let name = |i: usize| params.get(i).map_or_else(String::new, |p| p.name.clone());
        fixed
            .iter()
            .map(|f| FixedParameter {
                name: name(f.index),
                aliases: f.aliases.iter().map(|&a| name(a)).collect(),
            })
            .collect()
    }

    /// [`Session::named`] for a step that estimates the geometry, with the `d` of every
    /// Hayati pair: the model has no parameter for it (its row's `beta` takes its place, see
    /// [`PairParametrisation`]), so it stays at nominal too.
    pub(crate) fn named_geometric(&self, fixed: &[fit::Fixed]) -> Vec<FixedParameter> {
        let mut out = self.named(fixed);
        out.extend(replaced_by_beta(&self.model));
        out
    }

    /// The `nominal` step (the identifiable device and target coordinates; the others stay at
    /// the closed-form start), then the `geometric` one (every identifiable geometric
    /// parameter). Returns the steps, the geometric fit and its free and fixed parameters.
    pub(crate) fn geometric(&mut self) -> Result<Geometric, CalibError> {
        self.geometric_with(Folds::Refit)
    }

    /// [`Session::geometric`] whose `geometric` step's held-out figures are those of `folds`
    /// ([`Folds::Later`]: none yet, for a fit an outlier screen may discard; see
    /// [`Session::finish_geometric`]).
    pub(crate) fn geometric_with(&mut self, folds: Folds) -> Result<Geometric, CalibError> {
        let mut x = vec![0.0; self.model.parameter_count()];
        let measured = self.measured.clone();
        let nominal_columns = self.model.indices(|b| match b {
            Block::Device | Block::Session(_) => true,
            Block::Target(k) => measured[k],
            _ => false,
        });
        // The nominal step steps only where the data can tell device and targets apart (see
        // `fit::MIN_SENSITIVITY`): what it cannot stays at the closed-form start.
        let (nominal_free, nominal_fixed) = self.identify(&x, &nominal_columns)?;
        let mut step = self.step("nominal", &x, &nominal_free, None)?;
        step.report.fixed = self.named(&nominal_fixed);
        x = step.outcome.x.clone();
        let mut steps = vec![step.report];
        self.model.rebase(&mut x);
        self.device_nominal = self.model.device();
        self.targets_nominal = self.model.targets().iter().map(|t| t.1).collect();
        let geometric: Vec<usize> = self.model.indices(|b| !matches!(b, Block::Effect(_)));
        let (free, fixed) = self.identify(&x, &geometric)?;
        self.enough_for(&x, &geometric, free.len())?;
        let mut step = self.step_with("geometric", &x, &free, steps.last(), folds)?;
        step.report.fixed = self.named_geometric(&fixed);
        steps.push(step.report.clone());
        Ok(Geometric {
            steps,
            last: step,
            free,
            fixed,
        })
    }

    /// Gives the `geometric` step of `geo` (from [`Session::geometric_with`] with
    /// [`Folds::Later`]) the held-out figures [`Session::geometric_with`] gives it with
    /// `folds`.
    pub(crate) fn finish_geometric(
        &self,
        geo: &mut Geometric,
        folds: Folds,
    ) -> Result<(), CalibError> {
        let held = self.held_out_with(&geo.last.outcome.x, &geo.free, folds)?;
        set_val(&mut geo.last.report, &held);
        if let Some(step) = geo.steps.last_mut() {
            set_val(step, &held);
        }
        geo.last.held_out = held;
        Ok(())
    }

    /// Refuses data that leaves no residual degree of freedom for `columns`: as many free
    /// parameters (`free`, the data's rank) as measured coordinates, so the fit reproduces the
    /// data exactly and learns nothing. The error says how many samples the model needs: one
    /// more than a third of its generic rank, found at the same targets and random joint values.
    pub(super) fn enough_for(
        &self,
        x: &[f64],
        columns: &[usize],
        free: usize,
    ) -> Result<(), CalibError> {
        let cal = &self.prep.cal;
        let equations: usize = cal.iter().map(|o| o.observation.residual_count()).sum();
        if free < equations {
            return Ok(());
        }
        let per_sample = equations.div_ceil(cal.len().max(1)).max(1);
        let mut generic = free;
        let points_only = cal
            .iter()
            .all(|o| matches!(o.observation, Observation::Point { .. }));
        if let (true, Some(first)) = (points_only, cal.first()) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
            let targets: Vec<usize> = (0..self.measured.len())
                .filter(|&k| self.measured[k])
                .collect();
            let mut synthetic = Vec::new();
            for _ in 0..columns.len().max(1) {
                let q: Vec<f64> = (0..first.q.len())
                    .map(|_| rng.random_range(-std::f64::consts::PI..std::f64::consts::PI))
                    .collect();
                for &k in &targets {
                    synthetic.push(Observed::new(
                        q.clone(),
                        Observation::Point {
                            target: k,
                            point: self.model.point(x, &q, k),
                        },
                    ));
                }
            }
            if let Ok((f, _)) = identify(
                &self.model,
                &synthetic,
                x,
                columns,
                &self.scales,
                self.options,
            ) {
                generic = generic.max(f.len());
            }
        }
        Err(CalibError::TooFewSamples {
            what: format!(
                "geometric calibration ({generic} identifiable parameters, {per_sample} \
                 coordinates per sample; {free} would fit the data exactly)"
            ),
            needed: generic / per_sample + 1,
            found: cal.len(),
        })
    }

    /// The report at the fit `last` (its free parameters `free`, the fixed ones `fixed`).
    /// Effect parameters of effects listed in `hidden` are left out of the parameter list.
    pub(crate) fn report(
        &self,
        last: &FitOutcome,
        steps: Vec<StepReport>,
        fixed: Vec<fit::Fixed>,
        hidden: &[usize],
    ) -> Report {
        let model = &self.model;
        let x = last.x.clone();
        let mut notes = self.notes.clone();
        let noise_floor = match floor_or_why(&self.prep, self.options, last.free.len()) {
            Ok(f) => Some(f),
            Err(NoFloor::IdenticalRepeats(per_axis)) => {
                notes.push(format!(
                    "the noise floor cannot be estimated: the repeated poses are identical \
                     (pure error {per_axis:.1e} m per axis, below {:e} m), copies of one record \
                     rather than repeated measurements; give --sigma or a sigma column",
                    crate::MIN_SIGMA
                ));
                None
            }
            Err(NoFloor::Unknown) => None,
        };
        let mut parameters = estimates(model, &x, last, self.device_nominal, &self.targets_nominal);
        let hidden_names: Vec<&str> = model
            .parameters()
            .iter()
            .filter(|p| matches!(p.block, Block::Effect(e) if hidden.contains(&e)))
            .map(|p| p.name.as_str())
            .collect();
        parameters.retain(|p| !hidden_names.contains(&p.name.as_str()));
        let tree = model.tree_at(&x);
        let effect_free = last
            .free
            .iter()
            .any(|&c| matches!(model.parameters()[c].block, Block::Effect(_)));
        if effect_free {
            notes.push("effects are not part of the calibrated DH table".into());
        }
        let fixed = fixed
            .into_iter()
            .filter(|f| !hidden_names.contains(&model.parameters()[f.index].name.as_str()))
            .map(|f| FixedParameter {
                name: model.parameters()[f.index].name.clone(),
                aliases: f
                    .aliases
                    .iter()
                    .map(|&a| model.parameters()[a].name.clone())
                    .collect(),
            })
            .chain(replaced_by_beta(model))
            .collect();
        let (first, final_) = (&steps[0], &steps[steps.len() - 1]);
        let selected_effects = model
            .effects()
            .iter()
            .enumerate()
            .filter(|(e, (_, range))| {
                !hidden.contains(e) && range.clone().any(|c| last.free.contains(&c))
            })
            .map(|(_, (effect, _))| crate::effects::label_of(effect.as_ref()))
            .collect::<Vec<_>>();
        let covariance = last.covariance.as_ref().and_then(|c| {
            let names = last
                .free
                .iter()
                .map(|&i| model.parameters()[i].name.clone())
                .collect();
            crate::covariance::Covariance::new(names, c.clone()).ok()
        });
        notes.extend(crate::sessions::moved_note(
            self.session_names.len(),
            final_.rms,
            final_.val_rms,
        ));
        // The residuals at `x`, computed once for the sessions' figures and both tests of the
        // verdict (three passes over millions of samples before).
        let res = self.position_residuals(&x);
        let cal_d: Vec<f64> = res.iter().map(|r| r.norm()).collect();
        let sessions = self.session_reports_with(&x, &cal_d);
        drop(cal_d);
        let verdict = verdict_with(
            self,
            last,
            crate::findings::DEFAULT_ALPHA,
            noise_floor.as_ref(),
            final_.rms,
            &selected_effects,
            &res,
        );
        drop(res);
        Report {
            rms_before: first.rms,
            rms_after: final_.rms,
            val_rms_before: first.val_rms,
            val_rms_after: final_.val_rms,
            steps: steps.clone(),
            validation: self.validation.clone(),
            noise_floor,
            condition_number: last.condition_number,
            rank: last.rank,
            sigma_hat: last.sigma,
            length_scale: model.length_scale(),
            rank_tolerance: self.options.fit.rank_tolerance,
            parameters,
            fixed,
            parametrisation: model.pairs().to_vec(),
            calibrated: tree.trunk().clone(),
            device: model.device_at(&x),
            sessions,
            targets: (0..model.targets().len())
                .map(|k| (model.targets()[k].0.clone(), model.target_at(&x, k)))
                .collect(),
            target_rotations: (0..model.targets().len())
                .map(|k| {
                    model
                        .target_orientation(k)
                        .map(|_| model.target_rotation_at(&x, k))
                })
                .collect(),
            notes,
            tree: (!tree.branches().is_empty()).then_some(tree),
            candidates: vec![],
            selected_effects,
            diagnosis: None,
            outliers: None,
            verdict,
            covariance,
        }
    }
}

impl Session<'_> {
    /// Each session's frame and RMS at `x` (see [`crate::sessions::reports`]), given the
    /// distance of every calibration sample at `x` (`cal_d`, [`distances`]).
    pub(super) fn session_reports_with(
        &self,
        x: &[f64],
        cal_d: &[f64],
    ) -> Vec<crate::sessions::SessionReport> {
        let val_d = match self.validation {
            Validation::Split { .. } => split_distances(&self.model, x, &self.prep),
            _ => Vec::new(),
        };
        crate::sessions::reports(
            &self.model,
            x,
            &self.session_names,
            &self.prep,
            cal_d,
            &val_d,
        )
    }
}

/// The result of [`Session::geometric`].
pub(crate) struct Geometric {
    pub(crate) steps: Vec<StepReport>,
    pub(crate) last: StepResult,
    pub(crate) free: Vec<usize>,
    pub(crate) fixed: Vec<fit::Fixed>,
}

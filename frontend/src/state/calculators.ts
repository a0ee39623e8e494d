// The commissioning calculators and the gear-range preview (api/assist.py): pure arithmetic
// on the service (nc_sim/assist, nc_sim/spindle/gears.py), answered at once; the curve
// run-up runs on a copy of the machine like the other assistants. Apply: applyProposal.
import { http } from "../api/http";
import type {
  AssistResult,
  CurveFitRequest,
  CurveRunUpRequest,
  GearSelectionRequest,
  GearSelectionResult,
  MultiGainCalcRequest,
  ResolutionRequest,
  SpeedScalingRequest,
} from "../api/types";
import { runAssistant } from "./assist";
import { machineUrl } from "./session";

export interface CalculatorBodies {
  resolution: ResolutionRequest;
  "multi-gain-calc": MultiGainCalcRequest;
  "speed-scaling": SpeedScalingRequest;
  "curve-fit": CurveFitRequest;
  "curve-run-up": CurveRunUpRequest;
}
export type CalculatorName = keyof CalculatorBodies;

/** Run a calculator; rejects with the service's refusal (ApiError: 422 names the input). */
export function calculate<N extends CalculatorName>(name: N, body: CalculatorBodies[N]): Promise<AssistResult> {
  return runAssistant(name, body, "copy");
}

/** The stage the NC's rule selects for each S in turn, for the ranges as edited. */
export function previewGears(body: GearSelectionRequest): Promise<GearSelectionResult> {
  return http.post<GearSelectionResult>(machineUrl("/assist/gear-ranges"), body);
}
